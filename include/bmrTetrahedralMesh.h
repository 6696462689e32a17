/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef bmrTetrahedralMesh_h
#define bmrTetrahedralMesh_h

#include "BiomechanicalRegistrationExport.h"

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

/** \namespace bmr
 * \brief Plain C++ numerical core of the BiomechanicalRegistration module.
 *
 * Nothing in these headers exposes Eigen or CGAL types; the ITK classes in
 * this module are thin pipeline wrappers around these functions.
 * Units everywhere: millimeters (LPS physical space), kPa, mN (= kPa mm^2).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh
 */
namespace bmr {

/** \brief A labeled 4-node tetrahedral mesh in physical LPS millimeters.
 *
 * Shapes: \c points is 3N (x,y,z of node i at 3i..3i+2), \c tetrahedra is 4M
 * (node indices of element e at 4e..4e+3, positively oriented), \c labels is M.
 * \c boundaryFaces is 3F node indices of the faces of the mesh boundary,
 * oriented outward, and \c boundaryFaceLabels (F) gives the label of what lies
 * beyond each face: 0 for the outside of the meshed domain, otherwise the label
 * of an excluded region (a hollow organ or a fixed bone whose interior was left
 * out of the mesh). Optional per-node fields are empty or 3N long:
 * \c displacement [mm] and \c force [mN].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh
 */
struct BiomechanicalRegistration_EXPORT TetrahedralMesh
{
  std::vector<double>       points;
  std::vector<std::int32_t> tetrahedra;
  std::vector<std::int32_t> labels;
  std::vector<std::int32_t> boundaryFaces;
  std::vector<std::int32_t> boundaryFaceLabels;
  std::vector<double>       displacement;
  std::vector<double>       force;

  std::size_t
  GetNumberOfPoints() const
  {
    return points.size() / 3;
  }
  std::size_t
  GetNumberOfTetrahedra() const
  {
    return labels.size();
  }
};

/** Quality measures of a tetrahedral mesh. The radius ratio is 3 r_in / r_circ
 * (1 for the regular tetrahedron, 0 for a degenerate one). */
struct BiomechanicalRegistration_EXPORT MeshQuality
{
  double       minimumDihedralAngleDegrees{ 0.0 };
  double       maximumDihedralAngleDegrees{ 0.0 };
  double       minimumRadiusRatio{ 0.0 };
  double       meanRadiusRatio{ 0.0 };
  std::int64_t worstElement{ -1 };    ///< element with the smallest radius ratio
  std::int64_t sharpestElement{ -1 }; ///< element with the smallest dihedral angle
  double       meanEdgeLength{ 0.0 };
  double       volume{ 0.0 }; ///< total volume [mm^3]
};

/** Signed volume of element \a e [mm^3] (positive for the orientation used throughout). */
BiomechanicalRegistration_EXPORT double
TetrahedronVolume(const TetrahedralMesh & mesh, std::size_t e);

/** The distinct values of \a nodes (node or dof indices), ascending. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
                                 UniqueNodes(std::vector<std::int32_t> nodes);

/** Number of elements whose deformed volume (points + \a displacement [mm], 3 per node) is <= 0:
 * turned inside out, where linear elasticity no longer describes the tissue. */
BiomechanicalRegistration_EXPORT std::size_t
CountInvertedElements(const TetrahedralMesh & mesh, const std::vector<double> & displacement);

/** The inverted elements of one label, and where they lie: how many of them have a node on each other label (an
 * element of it, or an excluded region beyond a boundary face, such as a hollow organ's lumen): the organs the
 * crushed tissue lies against. */
struct BiomechanicalRegistration_EXPORT InvertedElements
{
  std::size_t                         count{ 0 };
  std::map<std::int32_t, std::size_t> touching; ///< other label -> inverted elements with a node on it
};

/** The inverted elements (CountInvertedElements()) by their label; labels without one are absent. */
BiomechanicalRegistration_EXPORT std::map<std::int32_t, InvertedElements>
InvertedElementsByLabel(const TetrahedralMesh & mesh, const std::vector<double> & displacement);

/** "label 1: 2081, of which 1650 against label 3 and 410 against label 4; label 2: 3" (InvertedElementsByLabel()),
 * for a warning that says where the deformation crushes tissue; each label by its name in \a names where it has one
 * ("soft_tissue: 2081, of which 1650 against bladder ..."); "" without an inverted element. */
BiomechanicalRegistration_EXPORT std::string
                                 InvertedElementsText(const std::map<std::int32_t, InvertedElements> & inverted,
                                                      const std::map<std::int32_t, std::string> &      names = {});

/** Minimum/maximum dihedral angle and radius ratio over all elements. */
BiomechanicalRegistration_EXPORT MeshQuality
ComputeMeshQuality(const TetrahedralMesh & mesh);

/** Checks the shapes of the arrays, index ranges, finite coordinates and
 * positive element volumes. Throws itk::ExceptionObject naming the first
 * offending element or node. */
BiomechanicalRegistration_EXPORT void
ValidateMesh(const TetrahedralMesh & mesh);

/** Removes the elements whose label is in \a excluded, records the faces between
 * kept and removed elements (and the faces on the outside) as boundary faces
 * with the label beyond them, and drops unused nodes. Node order is preserved
 * otherwise, so the result is deterministic. */
BiomechanicalRegistration_EXPORT TetrahedralMesh
ExtractSubmesh(const TetrahedralMesh & full, const std::vector<std::int32_t> & excluded);

/** Sorted list of the nodes on boundary faces whose beyond-label is \a label. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
                                 NodesOnBoundary(const TetrahedralMesh & mesh, std::int32_t label);

/** Sorted list of the nodes on the surface of the region of elements with
 * label \a label: its faces towards other labels and towards the boundary. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
                                 NodesOnLabelSurface(const TetrahedralMesh & mesh, std::int32_t label);

/** Faces (3 node indices each, oriented out of the region) of the surface of
 * the region with label \a label. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
                                 LabelSurfaceFaces(const TetrahedralMesh & mesh, std::int32_t label);

/** How finely the mesh resolves one label: its volume V [mm^3], the area A of its surface [mm^2] (faces
 * shared with no element of the same label), the mean edge length h of its elements [mm], and
 * \f$ n = 2V / (A h) \f$, the number of elements across it: a slab of thickness t has 2V / A = t, a ball
 * of radius R has 2V / A = 2R / 3. */
struct BiomechanicalRegistration_EXPORT LabelResolution
{
  std::int32_t label{ 0 };
  double       volume{ 0.0 };
  double       surfaceArea{ 0.0 };
  double       meanEdgeLength{ 0.0 };
  double       elementsAcross{ 0.0 };
};

/** LabelResolution of every label of \a mesh, in ascending label order. */
BiomechanicalRegistration_EXPORT std::vector<LabelResolution>
                                 ComputeLabelResolution(const TetrahedralMesh & mesh);

/** Number of connected components (elements sharing a face). \a componentOfNode
 * receives, when not null, the component index of every node. */
BiomechanicalRegistration_EXPORT std::size_t
ConnectedComponents(const TetrahedralMesh & mesh, std::vector<std::int32_t> * componentOfNode);

} // namespace bmr

#endif

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
#ifndef bmrMesher_h
#define bmrMesher_h

#include "bmrGridGeometry.h"
#include "bmrTetrahedralMesh.h"

#include <array>
#include <functional>
#include <map>
#include <utility>
#include <vector>

namespace bmr {

/** \brief Sizing and quality criteria for CGAL Mesh_3 (all lengths in mm).
 *
 * cellSize bounds the circumradius of the tetrahedra, facetSize the
 * circumradius of the surface triangles, facetDistance the distance between a
 * surface triangle and the true surface (the surface approximation error),
 * facetAngle (degrees) is the lower bound of surface triangle angles,
 * cellRadiusEdgeRatio the upper bound of circumradius / shortest edge.
 * cellSizePerLabel overrides cellSize inside given labels; facetSizePerLabel and
 * facetDistancePerLabel bound the surface triangles on the boundary of given
 * labels (a triangle between labels a and b gets the smallest of the global
 * bound and the bounds of a and b). optimize runs CGAL's sliver perturbation on
 * the elements with a dihedral angle below sliverBound, exude additionally its
 * (slower) sliver exudation; both without time limit, so that the result does
 * not depend on the machine's load.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh
 */
struct BiomechanicalRegistration_EXPORT MeshingParameters
{
  double                         cellSize{ 4.0 };
  double                         facetSize{ 4.0 };
  double                         facetDistance{ 0.75 };
  double                         facetAngle{ 25.0 };
  double                         cellRadiusEdgeRatio{ 3.0 };
  std::map<std::int32_t, double> cellSizePerLabel;
  std::map<std::int32_t, double> facetSizePerLabel;     ///< mm, on the surfaces bounding the label
  std::map<std::int32_t, double> facetDistancePerLabel; ///< mm, on the surfaces bounding the label
  bool                           optimize{ true };
  bool                           exude{ false };
  /** degrees: perturbation works on elements below this dihedral angle. 3 rather than CGAL's usual 5: several times
   * faster on the pelvis, and the recovered modulus barely moves (docs/history/benchmarks.md, "Sliver bound"). */
  double sliverBound{ 3.0 };
  /** degrees: MeshSceneLabels() refuses a mesh with a smaller dihedral angle, naming the element. Such a
   * sliver is all but flat: its stiffness matrix is near singular and the pull-back inside it ill defined. */
  double       minimumDihedralAngle{ 0.1 };
  unsigned int randomSeed{ 0 };
  /** Where MeshSceneLabels() and itk::LabelImageToTetrahedralMeshFilter put a label image's surfaces
   * (MeshLabelVolume() itself meshes the voxels'). Voxels: on the faces between voxels of different labels
   * (CGAL's labeled image), a staircase whose steps are a slice high. Distance: where the labels' interpolated
   * signed distances meet (DistanceLabelFunction(), scene key mesh.label_surfaces = "distance"), so that between
   * thick slices an outline moves from one slice's contour to the next instead of in terraces. */
  enum class LabelSurfaces
  {
    Voxels,
    Distance
  };
  LabelSurfaces labelSurfaces{ LabelSurfaces::Voxels };
  /** Local refinement: within refineDistance [mm] of the voxels labeled with one of refineNearLabels (measured on
   * the label grid), cells and surface facets are at most refineSize [mm]. For the thin tissue between an organ
   * whose modulus is estimated and the walls that load it, which a uniform size resolves only at a far higher
   * cost. Off when the list is empty or refineSize is 0. */
  std::vector<std::int32_t> refineNearLabels;
  double                    refineDistance{ 0.0 };
  double                    refineSize{ 0.0 };

  bool
  Refines() const
  {
    return !refineNearLabels.empty() && refineSize > 0.0;
  }
  bool
  HasFacetBoundsPerLabel() const
  {
    return !facetSizePerLabel.empty() || !facetDistancePerLabel.empty();
  }
  /** The per-label sizes [mm], each with its scene key (mesh.KEY), for code that treats them alike. */
  template<typename TSizes>
  using NamedSizes = std::array<std::pair<const char *, TSizes *>, 3>;
  NamedSizes<const std::map<std::int32_t, double>>
  SizesPerLabel() const
  {
    return { { { "cell_size_per_label_mm", &cellSizePerLabel },
               { "facet_size_per_label_mm", &facetSizePerLabel },
               { "facet_distance_per_label_mm", &facetDistancePerLabel } } };
  }
  NamedSizes<std::map<std::int32_t, double>>
  SizesPerLabel()
  {
    return { { { "cell_size_per_label_mm", &cellSizePerLabel },
               { "facet_size_per_label_mm", &facetSizePerLabel },
               { "facet_distance_per_label_mm", &facetDistancePerLabel } } };
  }
};

/** Meshes every non-zero label of a label volume with CGAL Mesh_3
 * (sequentially, fixed random seed: the same input gives the same mesh).
 * \a labels holds grid.GetNumberOfVoxels() values, index 0 fastest. The result
 * is in physical LPS mm (origin, spacing and direction cosines of \a grid
 * applied), every element carries its label, and interfaces between labels
 * share nodes. No element is excluded here; see ExtractSubmesh().
 * Throws itk::ExceptionObject when the volume holds no non-zero label or
 * CGAL produces no element. */
BiomechanicalRegistration_EXPORT TetrahedralMesh
MeshLabelVolume(const std::int32_t * labels, const GridGeometry & grid, const MeshingParameters & parameters);

/** Meshes the labeled domain given by \a labelAt (physical mm -> label, 0
 * outside) inside the ball (\a center, \a boundingRadius), with CGAL's exact
 * implicit-function domain. Used for analytic test geometries such as the
 * concentric spheres, where a voxelized surface would hide the convergence
 * order of the finite elements. */
BiomechanicalRegistration_EXPORT TetrahedralMesh
MeshImplicitLabels(const std::function<std::int32_t(double, double, double)> & labelAt,
                   const std::array<double, 3> &                               center,
                   double                                                      boundingRadius,
                   const MeshingParameters &                                   parameters);

/** Meshes the labeled domain given by \a labelAt (physical mm -> label, 0 outside) within the box of \a grid's voxel
 * centres (the extent MeshLabelVolume() meshes), seeding the refinement from \a gridLabels, the labels at those
 * centres (grid.GetNumberOfVoxels() values, index 0 fastest; normally labelAt's own voxelization). The surfaces are
 * labelAt's, not a label image's staircase: they stay put when the mesh is refined, so a field simulated on it
 * converges as the elements allow instead of following the staircase's corners (the phantom's truth). */
BiomechanicalRegistration_EXPORT TetrahedralMesh
MeshImplicitLabelsOnGrid(const std::function<std::int32_t(double, double, double)> & labelAt,
                         const GridGeometry &                                        grid,
                         const std::vector<std::int32_t> &                           gridLabels,
                         const MeshingParameters &                                   parameters);

} // namespace bmr

#endif

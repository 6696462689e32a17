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
#ifndef bmrPhantom_h
#define bmrPhantom_h

#include "bmrGridGeometry.h"
#include "bmrScene.h"

#include <iosfwd>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bmr {

/** Label values of the pelvis phantom (0 is air, outside the body). */
enum PelvisLabel : std::int32_t
{
  PelvisAir = 0,
  PelvisSoftTissue = 1,
  PelvisProstate = 2,
  PelvisBladder = 3,
  PelvisRectum = 4,
  PelvisBone = 5
};

/** Label values of the concentric-spheres phantom. */
enum SphereLabel : std::int32_t
{
  SphereOutside = 0,
  SphereOuterShell = 1,
  SphereInnerCore = 2
};

/** An implanted seed: a cylinder of the given length and diameter [mm] centered
 * at \c center (LPS mm) along the unit vector \c axis. */
struct BiomechanicalRegistration_EXPORT Seed
{
  std::array<double, 3> center{ { 0, 0, 0 } };
  std::array<double, 3> axis{ { 0, 0, 1 } };
  double                length{ 8.0 };
  double                diameter{ 1.5 };
};

/** A synthetic CT volume [HU, float] with its label map (int32) on one grid,
 * and the implanted seeds. */
struct BiomechanicalRegistration_EXPORT PhantomVolume
{
  GridGeometry              grid;
  std::vector<std::int32_t> labels;
  std::vector<float>        ct;
  std::vector<Seed>         seeds;
};

/** \brief How one patient's organs differ from the default pelvis phantom (the cohort generator draws it; every
 * other command uses the default).
 *
 * The prostate keeps its center (plus \c offset) and scales; the bladder and the rectum are moved by as much as
 * the prostate and the bladder grow towards them, so the soft tissue between the organs keeps about its default
 * thickness. MeasurePelvisClearance() tells whether a drawn anatomy keeps the organs apart. */
struct BiomechanicalRegistration_EXPORT PelvisAnatomy
{
  double                prostateScale{ 1.0 };  ///< the prostate's semi-axes 20 x 16 x 18 mm times this
  double                bladderScale{ 1.0 };   ///< the bladder's semi-axes 34 x 28 x 24 mm times this
  double                rectumRadius{ 13.0 };  ///< mm
  std::array<double, 3> offset{ { 0, 0, 0 } }; ///< of prostate, bladder and rectum together [mm, LPS]
};

/** The smallest distances [mm, between 1 mm voxel centers, at most 6] of an anatomy's organs to each other and
 * to the bones or the body outline, with the names of the closest pair. */
struct BiomechanicalRegistration_EXPORT PelvisClearance
{
  double      organToOrgan{ 6.0 };
  std::string closestOrgans;
  double      organToBoneOrOutline{ 6.0 };
  std::string closestToBoneOrOutline;
};

/** Voxelizes \a anatomy at 1 mm (no seeds) and measures its clearances. */
BiomechanicalRegistration_EXPORT PelvisClearance
MeasurePelvisClearance(const PelvisAnatomy & anatomy);

/** \brief Parameters of the pelvis phantom.
 *
 * The anatomy is defined in patient LPS coordinates (x towards the patient's
 * left, y posterior, z superior) around \c center (by default the physical
 * center of \c grid), so an oblique or anisotropic grid samples the same
 * physical anatomy. All lengths in mm, intensities in HU.
 */
struct BiomechanicalRegistration_EXPORT PelvisPhantomParameters
{
  GridGeometry          grid;
  bool                  useGridCenter{ true };
  std::array<double, 3> center{ { 0, 0, 0 } };
  std::uint64_t         seedPlacementSeed{ 1 }; ///< random seed for the implant positions
  unsigned int          numberOfSeeds{ 3 };
  double                noiseSigmaHU{ 0.0 }; ///< Gaussian noise added to the CT (0: none)
  std::uint64_t         noiseSeed{ 7 };
  PelvisAnatomy         anatomy; ///< the organs (default: the phantom every command but the cohort uses)

  PelvisPhantomParameters();
};

/** Parameters of the two concentric spheres of dissertation section 3.2.2:
 * an inner core (label 2) of radius \c innerRadius inside a shell (label 1)
 * of outer radius \c outerRadius, centered on the grid by default [mm]. */
struct BiomechanicalRegistration_EXPORT SpherePhantomParameters
{
  GridGeometry          grid;
  bool                  useGridCenter{ true };
  std::array<double, 3> center{ { 0, 0, 0 } };
  double                innerRadius{ 30.0 };
  double                outerRadius{ 37.5 };

  SpherePhantomParameters();
};

/** Builds the pelvis phantom: soft tissue (40 HU) in an elliptic body outline,
 * prostate (45 HU), a urine-filled bladder (10 HU) and a gas-filled rectum
 * (-700 HU) that the scene treats as hollow, pelvic bones (700 HU), air
 * (-1000 HU) and bright seeds (2500 HU, CT only, inside the prostate).
 * Deterministic for given parameters. */
BiomechanicalRegistration_EXPORT PhantomVolume
MakePelvisPhantom(const PelvisPhantomParameters & parameters);

/** Labels of the pelvis phantom's anatomy at physical points [mm] (3 per point), as the label map of
 * MakePelvisPhantom() holds them at voxel centers (seeds count as prostate). A deformed anatomy is
 * voxelized once with it: the label of a fixed voxel v is the label at its pull-back point v + d(v).
 * Resampling the already voxelized moving labels instead quantizes the surface twice (0.22 mm RMS
 * against 0.06 mm at 1 mm voxels), which is larger than the shape change of a stiff organ. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
PelvisLabelsAt(const PelvisPhantomParameters & parameters, const std::vector<double> & points);

/** Labels of the concentric spheres at physical points [mm] (3 per point), as MakeSpherePhantom() labels
 * voxel centers: a deformed anatomy voxelized once, as PelvisLabelsAt(). */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
SphereLabelsAt(const SpherePhantomParameters & parameters, const std::vector<double> & points);

/** The label of the anatomy at one physical point [mm] (x, y, z): what PelvisLabelsAt() and SphereLabelsAt() give
 * point by point. */
using PhantomLabelFunction = std::function<std::int32_t(double, double, double)>;

/** The pelvis phantom's anatomy as a function of the point (PelvisLabelsAt(), one point at a time), e.g. to mesh
 * the anatomy itself instead of its voxelization (MeshSceneFunction()). */
BiomechanicalRegistration_EXPORT PhantomLabelFunction
PelvisLabelFunction(const PelvisPhantomParameters & parameters);

/** The concentric spheres as a function of the point (SphereLabelsAt(), one point at a time). */
BiomechanicalRegistration_EXPORT PhantomLabelFunction
SphereLabelFunction(const SpherePhantomParameters & parameters);

/** Builds the concentric-spheres phantom (core 60 HU, shell 20 HU, air -1000 HU). */
BiomechanicalRegistration_EXPORT PhantomVolume
MakeSpherePhantom(const SpherePhantomParameters & parameters);

/** The pelvis phantom's scene: soft tissue 10 kPa (nu 0.35, the gauge), prostate \a prostateE [kPa] with
 * Poisson's ratio \a prostateNu, unknown within [20, 600] kPa when \a unknown (wide enough for the
 * dissertation's 50-350 kPa with room on both sides); bladder and rectum hollow and loaded, bone fixed, air
 * outside; the prostate, bladder and rectum surfaces matched with weight 1; a 25 mm region of interest and
 * the mesh sizes the estimation benchmark uses (cells 7 mm, prostate 4.5 mm, facets 6 mm, facet distance
 * 0.5 mm = half a 1 mm voxel). */
BiomechanicalRegistration_EXPORT Scene
PelvisPhantomScene(double prostateE, bool unknown, double prostateNu = 0.40);

/** The concentric spheres' scene: shell 10 kPa (nu 0.35, the gauge), core \a innerE [kPa] (nu 0.40),
 * unknown within [30, 300] kPa when \a unknown; the outer boundary loaded, both surfaces matched. */
BiomechanicalRegistration_EXPORT Scene
SpherePhantomScene(double innerE, bool unknown);

/** How the walls of the pelvis phantom move when the lumens fill (PelvisFillingLoads()). */
enum class WallFillingEnum : std::uint8_t
{
  /** Each wall along its own normals: the bladder along those of its ellipsoid, the rectum radially from its
   * axis and from the center of its dome. */
  AlongNormals,
  /** Radially from one point per organ: also slides the walls along themselves (the rectal wall next to the
   * prostate by up to 0.8 |d| along its axis), motion that no segmentation shows. */
  FromPoint
};

BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, WallFillingEnum value);

/** The truth's loads for a filling of the bladder by \a bladderMM and the rectum by \a rectumMM [mm]
 * (radial displacements about the phantom's own organ centers for \a parameters' grid). */
BiomechanicalRegistration_EXPORT std::vector<SceneLoad>
                                 PelvisFillingLoads(const PelvisPhantomParameters & parameters,
                                                    double                          bladderMM,
                                                    double                          rectumMM,
                                                    WallFillingEnum                 filling);

/** Physical center of the grid (center of the voxel box). */
BiomechanicalRegistration_EXPORT std::array<double, 3>
                                 GridCenter(const GridGeometry & grid);

/** Adds zero-mean Gaussian noise of standard deviation \a sigma to \a values,
 * from a self-contained generator so that the result is the same on every
 * platform and standard library for a given \a seed. */
BiomechanicalRegistration_EXPORT void
AddGaussianNoise(std::vector<float> & values, double sigma, std::uint64_t seed);

} // namespace bmr

#endif

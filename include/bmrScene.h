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
#ifndef bmrScene_h
#define bmrScene_h

#include "bmrLinearElasticModel.h"
#include "bmrMesher.h"

#include <iosfwd>
#include <set>
#include <string>
#include <vector>

namespace bmr {

/** The largest label voxel side [mm] at which an estimated modulus is stated with the rescans' interval. Its
 * coverage was shown on 1 mm phantoms; at 2-3 mm slices it was measured to miss the truth (docs/history/benchmarks.md,
 * "Clinical geometry"), so above this limit the registration states the interval of a thick-slice calibration where
 * one holds (itk::SliceCalibrations) and otherwise reports the modulus as not determined, with this reason, and the
 * voxel warning says the same. The registration's fields are not affected. */
constexpr double StatedModulusVoxelLimitMM = 1.5;

/** The reason a modulus is not stated from label voxels of up to \a coarsestVoxel mm (> \a limit, by default
 * StatedModulusVoxelLimitMM), in the words of both the warning and the report. */
BiomechanicalRegistration_EXPORT std::string
                                 VoxelLimitReason(double coarsestVoxel, double limit = StatedModulusVoxelLimitMM);

/** What a label of the moving label map is in the simulation. */
enum class LabelRoleEnum
{
  Material,        ///< simulated, known E [kPa] and nu
  UnknownMaterial, ///< simulated, E estimated within bounds [kPa], known nu
  Fixed,           ///< bone: interior left out, surface nodes get u = 0
  Hollow,          ///< lumen (bladder, rectum): left out, its wall may carry loads
  Outside          ///< air / background: left out
};

/** The tissue model of a scene (Scene::model). */
enum class MaterialModelEnum : std::uint8_t
{
  Linear,
  NeoHookean
};
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, MaterialModelEnum value);

struct BiomechanicalRegistration_EXPORT SceneLabel
{
  std::string   name;
  std::int32_t  value{ 0 };
  LabelRoleEnum role{ LabelRoleEnum::Material };
  double        youngsModulus{ 0.0 }; ///< kPa (initial value for an unknown material)
  double        poissonRatio{ 0.0 };
  double        lowerBound{ 0.0 }; ///< kPa, unknown materials only
  double        upperBound{ 0.0 }; ///< kPa, unknown materials only
};

struct BiomechanicalRegistration_EXPORT ObjectiveTerm
{
  std::string label;
  double      weight{ 1.0 };
};

/** A boundary condition applied by a forward simulation to the wall of an
 * excluded label (hollow organ) or to the outer boundary ("outside").
 * RadialDisplacement: every wall node moves by magnitude [mm] along the unit
 * vector from \c center [LPS mm] (positive = expansion, bladder filling).
 * With a non-zero \c axis (scene key "axis", normalized on reading) the
 * direction is taken from the nearest point of the half-line
 * {center - t axis, t >= 0} instead: a tube along the axis capped by a
 * hemisphere at \c center inflates along its own normals (rectal filling),
 * where a single center would also slide the tube's wall along its length.
 * With \c semiAxes (scene key "semi_axes_mm", all > 0) the direction is the
 * normal of the ellipsoid with these semi-axes about \c center, \f$ \propto
 * ((x-c)_i / a_i^2)_i \f$: an ellipsoidal bladder grows along its normals
 * (radial from the center, its wall would also slide along itself).
 * Pressure: a uniform pressure [kPa] on the wall, pushing into the tissue,
 * lumped to nodal forces [mN] (one third of each face's area per node). */
struct BiomechanicalRegistration_EXPORT SceneLoad
{
  enum class TypeEnum
  {
    RadialDisplacement,
    Pressure
  };
  std::string           surface;
  TypeEnum              type{ TypeEnum::RadialDisplacement };
  std::array<double, 3> center{ { 0, 0, 0 } };
  double                magnitude{ 0.0 };        ///< mm for RadialDisplacement, kPa for Pressure
  std::array<double, 3> axis{ { 0, 0, 0 } };     ///< RadialDisplacement: unit vector, or zero (radial from center)
  std::array<double, 3> semiAxes{ { 0, 0, 0 } }; ///< RadialDisplacement: ellipsoid semi-axes [mm], or zero
};

/** \brief A scene: what each label is, what carries loads, what is matched.
 *
 * Read from JSON (see docs/scenes.md). Every key is checked: an unknown
 * key, a wrong type, nu >= 0.5, E <= 0, a reference to an undefined label, or a
 * scene with nothing to hold it against rigid-body motion is rejected with an
 * itk::ExceptionObject naming the entry.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene
 */
struct BiomechanicalRegistration_EXPORT Scene
{
  std::string                name;
  std::vector<SceneLabel>    labels;
  std::string                gauge; ///< label whose modulus anchors the scale (default: first known material)
  std::vector<std::string>   forceSurfaces;
  std::vector<ObjectiveTerm> objective;
  std::vector<SceneLoad>     loads;
  std::string                movingLandmarks; ///< CSV file (LPS mm), relative to the scene file, optional
  std::string                fixedLandmarks;
  double                     roiMargin{ -1.0 }; ///< mm around the non-outside labels; < 0: whole image
  bool                       roiBoundaryFixed{ false };
  MeshingParameters          mesh;
  /** "formulation": "nodal_averaged_pressure" — the locking-free element formulation for every material
   * (bmr::LinearElasticModel); "standard" (default): plain P1 tetrahedra. */
  ElementFormulationEnum formulation{ ElementFormulationEnum::Standard };
  /** "model": "linear" (default; bmr::LinearForwardModel) or "neo_hookean" (geometrically nonlinear,
   * bmr::NeoHookeanForwardModel, standard P1 only): the tissue model of every simulation, estimation and
   * phantom of the scene. Both take the labels' E and nu and agree for small loads. */
  MaterialModelEnum model{ MaterialModelEnum::Linear };

  /** Warnings about the scene that are not errors: nu > 0.45 on standard P1 tetrahedra (volumetric
   * locking; use the nodal-averaged pressure formulation). */
  std::vector<std::string>
  Warnings() const;

  /** Warnings about estimating a modulus from label images whose smallest voxel side is \a finestVoxel mm; none
   * when no label has the role unknown_material. The modulus rests on sub-voxel changes of the organs' shapes: a
   * mesh whose surfaces may leave the labels' by more than half the finest voxel (mesh.facet_distance_mm) makes it
   * unreliable. (Voxels coarser than StatedModulusVoxelLimitMM: the registration pipeline warns and states no
   * modulus.) */
  std::vector<std::string>
  EstimationWarnings(double finestVoxel) const;

  /** Labels with the role unknown_material, in scene order: the moduli an estimation recovers. */
  std::vector<const SceneLabel *>
  UnknownLabels() const;
  /** The label whose modulus anchors the scale of the estimated moduli: \c gauge, or the first label with
   * the role material when the scene names none; nullptr when there is neither. */
  const SceneLabel *
  GaugeLabel() const;

  const SceneLabel *
  FindLabel(const std::string & name) const;
  const SceneLabel *
  FindLabelValue(std::int32_t value) const;
  /** Labels whose elements are left out of the FEM mesh (fixed, hollow, outside). */
  std::vector<std::int32_t>
  ExcludedLabels() const;
  /** Labels with the role Outside, which are not meshed at all (mapped to 0). */
  std::vector<std::int32_t>
  OutsideLabels() const;
  /** Checks the scene on its own; throws naming the offending entry. */
  void
  Validate() const;
  /** Checks the scene against the set of labels found in a label image \a what. */
  void
  ValidateAgainstLabels(const std::set<std::int32_t> & present, const std::string & what) const;
};

/** Parses a scene from JSON text; \a source names it in error messages. */
BiomechanicalRegistration_EXPORT Scene
ParseScene(const std::string & json, const std::string & source);

/** Reads and parses a scene file. */
BiomechanicalRegistration_EXPORT Scene
ReadScene(const std::string & fileName);

/** Serializes a scene to JSON text (the format ParseScene reads). */
BiomechanicalRegistration_EXPORT std::string
                                 SceneToJson(const Scene & scene);

BiomechanicalRegistration_EXPORT const char *
                                 LabelRoleName(LabelRoleEnum role);
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, LabelRoleEnum value);
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, SceneLoad::TypeEnum value);

/** Comma-separated labels, by value or (with a scene) by name; "none" gives an empty list. Throws naming an
 * entry that is neither. */
BiomechanicalRegistration_EXPORT std::vector<std::int32_t>
                                 ParseLabelList(const std::string & text, const Scene * scene);

} // namespace bmr

#endif

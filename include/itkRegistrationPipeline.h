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
#ifndef itkRegistrationPipeline_h
#define itkRegistrationPipeline_h

#include "bmrElasticityEstimator.h"
#include "itkModulusInterval.h"
#include "itkSimulationPipeline.h"

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace itk {

// A segmented pair registered with joint estimation of the unknown moduli: RegisterSegmentedPair().

struct MovingAnatomyMeshes;

/** Settings of RegisterSegmentedPair(); the defaults are biomechreg register's.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT RegistrationSettings
{
  bmr::EstimatorSettings estimator;
  bmr::WallLoadSettings  walls;
  double                 coarseFactor{ 1.6 }; ///< coarse (sweep) mesh sizes = scene's x this; <= 1: no coarse mesh
  double                 meshScale{ 1.0 };    ///< mesh sizes = scene's x this (> 1: coarser, faster)
  UncertaintySettings    uncertainty;
  bool pushField{ false }; ///< also the push field (moving -> fixed) in state.push (a second rasterization)
  /** Thick slices (ThickSlices(): 2-3 mm slices of a 1 mm in-plane CT): both scans' organs between their slices by
   * shape-based interpolation (InterpolateLabelSlices()): the moving anatomy is meshed from its interpolated
   * labels, the fixed organs' distance maps and the rescans' anatomy are those of the interpolated fixed labels.
   * Without thick slices nothing changes. Off by default: on phantom pairs at 1 x 1 x 3 mm it halved the inverted
   * elements but made the modulus more biased (docs/history/benchmarks.md, "Clinical geometry"), and no thick slices'
   * calibration measured it, so with it the modulus is reported as not determined (SliceCalibrationOf). */
  bool interpolateSlices{ false };
  /** The estimated state's per-element moduli, von Mises stress and Dirichlet flags in state.simulation, which
   * mesh.vtu holds; false leaves them empty (state.simulation then has the nodal displacement and force only). */
  bool elementState{ true };
  /** The moving anatomy's meshes, made beforehand by MeshMovingAnatomy() for these labels, scene and settings
   * (not owned; must outlive the call). Null (default): RegisterSegmentedPair() meshes them itself. */
  const MovingAnatomyMeshes * meshes{ nullptr };

  /** Throws itk::InvalidArgumentError naming the first setting out of its range (estimator, walls and uncertainty
   * included): coarseFactor in (0, 10], meshScale in [0.25, 4], limitElementInversion only with one parameter per
   * wall node. RegisterSegmentedPair() calls it; `biomechreg register` reports it as a usage error. */
  void
  Validate() const;
};

/** \brief The moving anatomy's meshes for RegisterSegmentedPair(), made before the fixed scan is there.
 *
 * A planning scan is segmented long before the daily scans arrive, and every mesh a registration needs depends
 * on the moving labels, the scene and the settings only: the fit's mesh, the coarse mesh of the sweep and the
 * re-meshed models of the stated interval's resamples (together several times the fit's own meshing).
 * MeshMovingAnatomy() makes them once, beforehand or on a spare core while other work runs, and every
 * registration against that planning scan takes them through RegistrationSettings::meshes. They are the meshes
 * RegisterSegmentedPair() would make itself (the same sizes and mesher seeds), so the results are the same bit
 * for bit. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT MovingAnatomyMeshes
{
  bmr::TetrahedralMesh              fine;      ///< the fit's mesh
  bmr::TetrahedralMesh              coarse;    ///< the sweep's; empty when there is no modulus to sweep
  std::vector<bmr::TetrahedralMesh> resamples; ///< the stated interval's, by resample; empty without resamples
  std::uint64_t fingerprint{ 0 };    ///< of the labels, scene and settings they were made for (checked on use)
  std::vector<PipelineStage> stages; ///< the meshing's wall times [s]
};

/** Meshes \a movingLabels for RegisterSegmentedPair() with \a scene and \a settings (MovingAnatomyMeshes). Throws
 * itk::ExceptionObject when the labels are missing or the scene is invalid, as RegisterSegmentedPair() would.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT MovingAnatomyMeshes
MeshMovingAnatomy(const BiomechanicalLabelImageType * movingLabels,
                  const bmr::Scene &                  scene,
                  const RegistrationSettings &        settings = RegistrationSettings());

/** What RegisterSegmentedPair() found. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT RegistrationResult
{
  SimulationResult                       state;              ///< the estimated state: mesh, fields, stress
  bmr::EstimationResult                  estimation;         ///< moduli, loads, history, identifiability, uncertainty
  std::vector<bmr::UnknownModulus>       unknowns;           ///< in the order of estimation.youngsModuli
  std::map<std::string, double>          youngsModulus;      ///< kPa, by unknown label name
  std::map<std::string, double>          modulusUncertainty; ///< standard deviation of log E (curvature), by name
  std::map<std::string, ModulusInterval> modulusInterval;    ///< the stated interval, by name (method not None)
  std::string                            gaugeLabel;
  double                                 gaugeModulus{ 0.0 }; ///< kPa
  BiomechanicalLabelImageType::Pointer   warpedLabels;        ///< nearest neighbor
  BiomechanicalCTImageType::Pointer      warpedCT;            ///< linear; null without a moving CT
  ImageBase<3>::Pointer                  movingGrid;          ///< the moving labels' grid (the field points into it)
  std::map<std::string, double>          dice;                ///< warped against fixed labels, by name
  /** By label name, its volume [mL] in the moving and in the fixed labels (a filling the scans show). */
  std::map<std::string, std::array<double, 2>> labelVolumeML;
  /** Label \a name's volume change between the scans [mL] (fixed minus moving, from labelVolumeML): the filling
   * term of the thick slices' calibration for SliceCalibrationFillingOrgan (SliceCalibratedInterval()); NaN when
   * the scene has no such label or neither scan shows it. */
  double
  VolumeChangeML(const std::string & name) const;
  /** Whether the organs were interpolated between thick slices (RegistrationSettings::interpolateSlices and
   * a moving or fixed label image with ThickSlices()). */
  bool   slicesInterpolated{ false };
  double jacobianMinimum{ 0.0 };
  double jacobianNonPositiveFraction{ 0.0 };
};

/** Standard deviation of log E above which RegisterSegmentedPair() warns: one sigma beyond the 10 % the
 * estimate aims at. */
constexpr double BiomechanicalUncertaintyWarningLogSigma = 0.1;

/** Everything biomechreg register does but reading and writing: the images' overlap and the scene are
 * checked; distance maps of the fixed labels; the moving labels meshed (and a coarse mesh for the sweep
 * when a modulus is unknown); FEMElasticityOptimizer; the pull-back and push fields; the moving labels (and
 * CT, when given) warped; Dice per organ and the Jacobian of the pull-back field; warnings. \a movingCT may
 * be null. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT RegistrationResult
RegisterSegmentedPair(const BiomechanicalLabelImageType * movingLabels,
                      const BiomechanicalLabelImageType * fixedLabels,
                      const BiomechanicalCTImageType *    movingCT,
                      const bmr::Scene &                  scene,
                      const RegistrationSettings &        settings = RegistrationSettings(),
                      PipelineObserver *                  observer = nullptr);

/** As above, with probabilistic or partial-volume fixed segmentations for some objective organs: their distance
 * maps come from the 0.5 level of \a fixedProbabilities (ComputeProbabilityDistanceMap, a sub-voxel surface)
 * instead of the fixed labels' staircase, and the bootstrap's resamples give those organs fractions too. The
 * fixed labels still define the output grid and serve the other organs and Dice. Throws when a name is not an
 * objective organ of the scene. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT RegistrationResult
RegisterSegmentedPair(const BiomechanicalLabelImageType * movingLabels,
                      const BiomechanicalLabelImageType * fixedLabels,
                      const OrganProbabilityImages &      fixedProbabilities,
                      const BiomechanicalCTImageType *    movingCT,
                      const bmr::Scene &                  scene,
                      const RegistrationSettings &        settings = RegistrationSettings(),
                      PipelineObserver *                  observer = nullptr);

/** \a scene with every mesh size (cell, facet, facet distance, per-label cell sizes, the local refinement's size but
 * not its distance) multiplied by \a factor. */
BiomechanicalRegistration_EXPORT bmr::Scene
                                 ScaledMeshSizes(bmr::Scene scene, double factor);

} // namespace itk

#endif

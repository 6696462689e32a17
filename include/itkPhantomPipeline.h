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
#ifndef itkPhantomPipeline_h
#define itkPhantomPipeline_h

#include "bmrLandmarks.h"
#include "bmrPhantom.h"
#include "itkPipelineTypes.h"

#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace itk {

// Phantom pairs with their ground truth: MakePhantomPair(), DrawPhantomSet().

/** Settings of a phantom pair; the defaults are biomechreg phantom's.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT PhantomSettings
{
  enum class AnatomyEnum : std::uint8_t
  {
    Pelvis,
    Spheres
  };
  AnatomyEnum       anatomy{ AnatomyEnum::Pelvis };
  bmr::GridGeometry grid{ bmr::PelvisPhantomParameters().grid };
  double            prostateE{ 50.0 };  ///< kPa (the core of the spheres)
  double            prostateNu{ 0.40 }; ///< the estimation scene assumes 0.40
  /** kPa: the truth's soft tissue (the spheres' outer shell). The estimation scene assumes 10 kPa whatever this is,
   * so that a truth with 20 kPa tests a wrong assumption (dissertation Table 3.7: the estimate scales with it). */
  double               tissueE{ 10.0 };
  double               bladderMM{ 4.0 }; ///< filling [mm]; the spheres: inward motion of the outer boundary
  double               rectumMM{ 3.0 };
  bmr::WallFillingEnum filling{ bmr::WallFillingEnum::AlongNormals };
  double               tumourFraction{ 0.0 }; ///< volume fraction of the prostate taken by a stiffer tumour
  double               tumourE{ 100.0 };      ///< kPa
  double               bladderKPa{ 0.0 };     ///< > 0: bladder and rectum loaded by pressure [kPa] instead
  double               rectumKPa{ 0.0 };
  double               noiseHU{ 10.0 };
  std::uint64_t        seed{ 1 };
  unsigned int         numberOfSeeds{ 3 };
  double               trackingNoiseMM{ 0.5 }; ///< sigma of the tracked treatment markers' noise [mm] per axis
  bool fractions{ false }; ///< also the fixed scan's volume fraction of every objective organ (fixedFractions)
  /** Also the area fractions of every objective organ's exact outlines on each fixed slice, as an RTSTRUCT drawn on
   * the fixed scan carries them (fixedContourFractions). */
  bool   contourFractions{ false };
  double truthRefinement{ 0.5 }; ///< the truth's mesh sizes relative to the scene's (facet distance x 0.8 more)
  /** What the truth's mesh follows: the moving label map's voxels (Voxels), or the analytic anatomy those voxels
   * sample (Anatomy, the default: bmr::MeshSceneFunction(), smooth surfaces that stay put when the truth is refined,
   * so that its field converges as the elements allow). The fixed labels voxelize the deformed anatomy either way. */
  enum class TruthGeometryEnum : std::uint8_t
  {
    Voxels,
    Anatomy
  };
  TruthGeometryEnum truthGeometry{ TruthGeometryEnum::Anatomy };
  /** mm: the truth's cells and surface facets at most truthRefineSize within truthRefineDistance of the organ whose
   * modulus is estimated (the prostate; the spheres' core), where the tissue between it and the loaded walls is thin
   * (bmr::MeshingParameters::refineNearLabels); 0: no local refinement. The pelvis's default, 1.25 mm within 6 mm
   * of the 0.5x mesh, is the converged truth: refined further (0.4x, 0.7 mm) its field changes by at most 0.8 % of its
   * maximum in the prostate (docs/history/benchmarks.md, "Truth meshed from the analytic anatomy"). The spheres': 0. */
  double truthRefineDistance{ 6.0 };
  double truthRefineSize{ 1.25 };
  /** The fixed scan's grid is the moving one shifted by U(-this, this) voxels along each axis (seeded by seed):
   * two scans are not aligned to the voxel. 0 (default): the same grid, whose quantization then partly cancels
   * between the scans where the tissue moves little. */
  double fixedGridShiftVoxels{ 0.0 };
  /** The tissue model of the truth and of the scene handed to the estimator (bmr::Scene::model). */
  bmr::MaterialModelEnum model{ bmr::MaterialModelEnum::Linear };
  /** The patient's organs (pelvis only; the default anatomy unless a cohort draws another). */
  bmr::PelvisAnatomy organs;
  /** Seeds the moving (planning) scan: its implant positions and its CT noise; 0 (default): \c seed. The fractions
   * of one patient share it, so that they are all registered from one planning scan. */
  std::uint64_t planningSeed{ 0 };

  /** The defaults of an anatomy: the pelvis as above; the spheres on their own 96^3 grid of 1 mm, the outer
   * surface pressed 1.5 mm inwards (bladderMM). */
  static PhantomSettings
  Defaults(AnatomyEnum anatomy);
};

BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, PhantomSettings::AnatomyEnum value);

/** A moving/fixed pair with its ground truth. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT PhantomPair
{
  BiomechanicalCTImageType::Pointer    movingCT, fixedCT;
  BiomechanicalLabelImageType::Pointer movingLabels, fixedLabels;
  BiomechanicalFieldType::Pointer      truthField; ///< fixed -> moving [mm]
  bmr::Scene                           scene;      ///< what the estimator sees (prostate modulus unknown)
  bmr::Scene                           truthScene; ///< known moduli and wall loads
  std::vector<bmr::Landmark>           movingLandmarks, fixedLandmarks; ///< seed centers [mm, LPS]
  /** The fixed seed centers as a tracking system reports them: with Gaussian noise of
   * PhantomSettings::trackingNoiseMM per axis, seeded by the phantom's seed (itk::AddTrackingNoise). */
  std::vector<bmr::Landmark> trackedLandmarks;
  OrganProbabilityImages     fixedFractions;        ///< per objective organ, with PhantomSettings::fractions
  OrganProbabilityImages     fixedContourFractions; ///< per objective organ, with PhantomSettings::contourFractions
  std::size_t                truthTetrahedra{ 0 }, truthNodes{ 0 };
  /** How far each loaded wall moved in the truth [mm]: the largest and the mean |u| over the truth mesh's nodes on
   * the wall, per load surface. For pressure loads the filling a pressure made (bladder filling = its max). */
  std::map<std::string, std::array<double, 2>> wallMotionMaxMeanMM;
  std::vector<PipelineStage>                   stages;
};

/** Makes a pair: the fixed images are the moving ones warped by a forward simulation with known moduli on
 * a finer, independently meshed model (another random seed of the mesher), the fixed labels voxelized once
 * from the deformed analytic anatomy (pelvis), the fixed CT with its own noise; the seeds moved with the
 * simulated displacement. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT PhantomPair
MakePhantomPair(const PhantomSettings & settings, PipelineObserver * observer = nullptr);

/** What MakePhantomPair() calls as soon as the moving labels and the estimation scene (PhantomPair::scene) exist,
 * before the truth is meshed and simulated (most of its time, on one core): e.g. to mesh the moving anatomy for
 * the registration alongside (MeshMovingAnatomy()). The image lives as long as the pair. */
using PhantomMovingReady =
  std::function<void(const BiomechanicalLabelImageType * movingLabels, const bmr::Scene & scene)>;

/** As above, reusing the truth's mesh: an empty \a truthMesh receives the mesh made, a non-empty one is used
 * instead of meshing again. Only for pairs of one planning anatomy (the same grid, planningSeed, anatomy, model,
 * tumour and truthRefinement, as the fractions of one phantom-cohort patient), whose truth meshes are identical:
 * CGAL meshes the same labels with the same sizes and seed into the same mesh. The fillings, moduli and noise may
 * differ. \a movingReady (may be empty) is called once the moving images exist (PhantomMovingReady).
 * \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT PhantomPair
MakePhantomPair(const PhantomSettings &    settings,
                PipelineObserver *         observer,
                bmr::TetrahedralMesh &     truthMesh,
                const PhantomMovingReady & movingReady = PhantomMovingReady());

/** The ranges DrawPhantomSet() draws from: [low, high] each. \ingroup BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT PhantomSetRanges
{
  std::array<double, 2> prostateE{ { 50.0, 300.0 } }; ///< kPa, log-uniform (whole kPa)
  std::array<double, 2> bladderMM{ { 3.0, 8.0 } };    ///< mm, uniform (0.01 mm)
  std::array<double, 2> rectumMM{ { 2.0, 5.0 } };     ///< mm, uniform (0.01 mm)
};

/** \a count pelvis phantom settings for a comparison (biomechreg phantom-set), drawn reproducibly from \a seed:
 * prostate modulus log-uniform over \a ranges.prostateE (whole kPa), bladder and rectum fillings uniform over their
 * ranges (0.01 mm), noise and seed placement seeded by seed * 1000 + k + 1. The default ranges give the sets of
 * earlier versions. Throws when a range is empty, reversed or not positive. \ingroup
 * BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT std::vector<PhantomSettings>
DrawPhantomSet(unsigned int count, std::uint64_t seed, const PhantomSetRanges & ranges = {});

} // namespace itk

#endif

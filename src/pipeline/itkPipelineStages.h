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
#ifndef itkPipelineStages_h
#define itkPipelineStages_h

// Stages shared by the pipelines (private to src/pipeline).
#include "bmrParallel.h"
#include "bmrRandom.h"
#include "itkBiomechanicalPipelines.h"
#include "itkFEMElasticityOptimizer.h"
#include "itkImageWarper.h"
#include "itkMultiThreaderBase.h"
#include "itkSceneDistanceMaps.h"

#include "bmrStopwatch.h"

#include <atomic>
#include <functional>
#include <mutex>
#include <random>
#include <cstdint>

namespace itk {
namespace pipeline {

using bmr::Uniform; // bmrRandom.h

/** Times the stages of a pipeline into a list and tells the observer. */
class StageClock
{
public:
  StageClock(PipelineObserver * observer, std::vector<PipelineStage> & stages)
    : m_Observer(observer)
    , m_Stages(stages)
  {}
  void
  Begin(const std::string & name);
  void
  End(const std::string & detail = std::string());
  void
  Add(const std::string & name, double seconds)
  {
    m_Stages.push_back({ name, seconds });
  }
  /** A stage timed elsewhere (\a seconds), told to the observer as it ends, with \a detail. */
  void
  Record(const std::string & name, double seconds, const std::string & detail)
  {
    m_Stages.push_back({ name, seconds });
    if (m_Observer)
    {
      m_Observer->StageBegin(name);
      m_Observer->StageEnd(name, seconds, detail);
    }
  }
  void
  Warn(std::vector<std::string> & list, const std::vector<std::string> & warnings);
  PipelineObserver *
  GetObserver() const
  {
    return m_Observer;
  }

private:
  PipelineObserver *           m_Observer;
  std::vector<PipelineStage> & m_Stages;
  std::string                  m_Current;
  bmr::SteadyClock::time_point m_Start;
};

/** Meshes the labels for the scene (CGAL Mesh_3), as one stage. */
bmr::TetrahedralMesh
MeshLabelImage(const BiomechanicalLabelImageType * labels,
               const bmr::Scene &                  scene,
               StageClock &                        clock,
               const std::string &                 stage);

/** A mesh made beside the caller (CGAL meshes on one core; a bmr::BackgroundTask on TBB's pool) while it does other
 * work, when more than one thread may run; otherwise made in Take(). The mesh is the same either way. */
class BackgroundMesh
{
public:
  BackgroundMesh(const BiomechanicalLabelImageType * labels, const bmr::Scene & scene);
  ~BackgroundMesh();
  BackgroundMesh(const BackgroundMesh &) = delete;
  BackgroundMesh &
  operator=(const BackgroundMesh &) = delete;
  /** The mesh, as stage \a stage of \a clock; the stage's time is the wait for it, so that the stages still add up
   * to the wall time, and its detail says how long the meshing took in all. Rethrows the mesher's exception. */
  bmr::TetrahedralMesh
  Take(StageClock & clock, const std::string & stage);
  /** Whether the mesh is being made beside the caller (until it is taken). */
  bool
  Alongside() const
  {
    return m_Task != nullptr;
  }
  /** The mesh made alongside, waiting for it (from any thread); \a detail says what was made. Only when
   * Alongside(); rethrows the mesher's exception. */
  bmr::TetrahedralMesh
  TakeAlongside(std::string & detail);
  /** How long the meshing took on its thread [s], once taken. */
  double
  MeshingSeconds() const
  {
    return m_Seconds;
  }

private:
  struct Made
  {
    bmr::TetrahedralMesh mesh;
    std::string          detail;
    double               seconds{ 0.0 };
  };
  static Made
  Make(const BiomechanicalLabelImageType * labels, const bmr::Scene & scene);

  const BiomechanicalLabelImageType *  m_Labels;
  bmr::Scene                           m_Scene;
  Made                                 m_Made;
  std::unique_ptr<bmr::BackgroundTask> m_Task; // null: not alongside, or taken
  double                               m_Seconds{ 0.0 };
};

/** The pull-back field of result.mesh's displacement on \a fixedReference's grid and, when asked, the push
 * field on \a movingReference's grid; an inverted-element warning names \a scene's labels. */
void
ComputeFields(SimulationResult &   result,
              const ImageBase<3> * fixedReference,
              const ImageBase<3> * movingReference,
              bool                 pushField,
              const bmr::Scene &   scene,
              StageClock &         clock);

/** How many threads the stated interval's resamples may use: UncertaintySettings::threads, or ITK's default. */
inline unsigned int
ResampleThreads(const UncertaintySettings & u)
{
  return u.threads > 0 ? u.threads : MultiThreaderBase::GetGlobalDefaultNumberOfThreads();
}

/** What a resample of the stated interval draws at random, each from a stream of its own: whatever makes one part
 * of a resample beforehand (ResampleMeshPrefetch, RescanMapsPrefetch) draws that part alone, and a resample's draws
 * do not depend on which other parts it draws or in which order. */
enum class ResampleDraw : std::uint32_t
{
  MeshSizes = 1,  ///< the scale of the fine mesh's sizes (ResampleMeshScene())
  Grid = 2,       ///< the rescan's voxel grid: shift, rotation, spacing
  WallMotion = 3, ///< the bootstrap's perturbed wall motion
};

/** The random numbers \a draw of resample \a k of the stated interval: the same seed, k and draw, the same numbers.
 * std::seed_seq mixes the four words as the C++ standard fixes, so the streams are the same on every platform. */
inline std::mt19937_64
ResampleRandom(const UncertaintySettings & u, unsigned int k, ResampleDraw draw)
{
  std::seed_seq words{ static_cast<std::uint32_t>(u.seed),
                       static_cast<std::uint32_t>(u.seed >> 32),
                       static_cast<std::uint32_t>(k),
                       static_cast<std::uint32_t>(draw) };
  return std::mt19937_64(words);
}

/** The scene of resample \a k's fine mesh: the scene's mesh sizes scaled by U(1 - jitter, 1 + jitter), drawn from
 * the resample's ResampleDraw::MeshSizes stream. */
bmr::Scene
ResampleMeshScene(const bmr::Scene & scene, const UncertaintySettings & u, unsigned int k);

/** \brief The resamples' fine meshes, made on another thread while the fit runs.
 *
 * The fit keeps about two cores busy (its solves' bins and tiles, between serial steps), and the mesher is serial.
 * The resamples' meshes depend only on the moving labels, the scene and the resample's random numbers
 * (ResampleMeshScene()), not on the fit: meshed here first, side by side on the budget beyond two cores (one after
 * the other on a smaller machine), they are the same meshes the resamples would make, and the results do not
 * change. */
class ResampleMeshPrefetch
{
public:
  ResampleMeshPrefetch(const BiomechanicalLabelImageType * movingLabels,
                       const bmr::Scene &                  scene,
                       const UncertaintySettings &         u);
  ~ResampleMeshPrefetch();
  ResampleMeshPrefetch(const ResampleMeshPrefetch &) = delete;
  ResampleMeshPrefetch &
  operator=(const ResampleMeshPrefetch &) = delete;

  /** Stops after the mesh under way and hands over the meshes made, by resample (empty where none was). */
  std::vector<bmr::TetrahedralMesh>
  Finish();

private:
  std::vector<bmr::TetrahedralMesh> m_Meshes;
  std::atomic<bool>                 m_Stop{ false };
  bmr::BackgroundTask               m_Task;
};

class RescanMapsPrefetch;

/** What an estimation runs on: the fine mesh (and a coarse one for the sweep, or null), the scene and the settings. */
struct EstimationSetup
{
  const bmr::TetrahedralMesh * fine{ nullptr };
  /** Or, when fine is null, the function that returns it once the sweep on the coarse mesh is done (the fine mesh
   * made beside the sweep; FEMElasticityOptimizer::SweepCoarseMesh()). */
  std::function<bmr::TetrahedralMesh()> fineAfterSweep;
  const bmr::TetrahedralMesh *          coarse{ nullptr };
  const bmr::Scene *                    scene{ nullptr };
  const RegistrationSettings *          settings{ nullptr };
  std::vector<std::string>              probabilityOrgans; ///< objective organs whose fixed data are probabilities
  const OrganProbabilityImages *        probabilities{ nullptr }; ///< those data (may be null when there are none)
  /** When given (a resample's estimation), the outer search starts here instead of sweeping: moduli [kPa] by
   * name and the relative curvature of the estimate (FEMElasticityOptimizer::SetWarmStart). */
  std::map<std::string, double> warmStartModuli;
  double                        warmStartRelativeCurvature{ 0.0 };
  /** The resamples' meshes, made while the fit ran (may be null: each resample meshes its own). */
  ResampleMeshPrefetch * prefetch{ nullptr };
  /** Or made beforehand (MovingAnatomyMeshes::resamples; may be null). */
  const std::vector<bmr::TetrahedralMesh> * resampleMeshes{ nullptr };
  /** The rescans' distance maps, made while the fit runs (may be null: each rescan makes its own). */
  RescanMapsPrefetch * rescanMaps{ nullptr };
  /** FEMElasticityOptimizer::SetNumberOfFineSolveThreads(): fewer than the budget when other work runs beside the
   * fit (a resample's estimation: one, beside the others). */
  unsigned int fineSolveThreads{ 1 };
  /** Whether the label voxels allow a stated modulus (UncertaintySettings::statedVoxelLimitMM): without, no
   * uncertainty of it is computed, neither resamples nor the curvature. */
  bool statesModulus{ true };
  /** Where the resamples' limit rules them out: the thick slices' calibration that holds for both scans
   * (FindSliceCalibration()), or null: the modulus is then not determined. */
  const SliceCalibration * sliceCalibration{ nullptr };
};

/** Refuses (itk::InvalidArgumentError naming RegisterSegmentedPair) a moving and a fixed image that do not overlap in
 * physical space (a wrong origin, a wrong file): they cannot be registered. */
void
CheckOverlap(const ImageBase<3> * moving, const ImageBase<3> * fixed);

/** The objective organs' distance maps by name. */
using DistanceMaps = std::map<std::string, Image<float, 3>::Pointer>;

/** \brief The rescans' distance maps (UncertaintyMethodEnum::Rescan), made beside the fit (a bmr::BackgroundTask):
 * they need only the fixed labels. The same maps, by rescan, as BootstrapModuli() would make itself. */
class RescanMapsPrefetch
{
public:
  /** Starts with \a setup's scene, settings and probabilities, which must outlive this object. */
  RescanMapsPrefetch(const BiomechanicalLabelImageType * fixedLabels, const EstimationSetup & setup);
  ~RescanMapsPrefetch();
  RescanMapsPrefetch(const RescanMapsPrefetch &) = delete;
  RescanMapsPrefetch &
  operator=(const RescanMapsPrefetch &) = delete;

  /** Waits for the maps, by rescan; rethrows what their making threw. */
  std::vector<DistanceMaps>
  Finish();

private:
  std::atomic<bool>         m_Stop{ false };
  std::vector<DistanceMaps> m_Maps;
  bmr::BackgroundTask       m_Task;
};

/** Whether the registration of \a scaledScene (mesh sizes scaled by settings.meshScale) sweeps on a coarse mesh. */
bool
UsesCoarseMesh(const bmr::Scene & scaledScene, const RegistrationSettings & settings);

/** Whether its stated interval re-meshes the moving anatomy per resample (rescans and bootstrap). */
bool
UsesResampleMeshes(const bmr::Scene & scaledScene, const RegistrationSettings & settings);

/** What MovingAnatomyMeshes depend on: the moving labels and their grid, the scene (\a scene as given, before
 * settings.meshScale) and the mesh settings (scale, coarse factor, the resamples' method, count, seed and jitter). */
std::uint64_t
MovingAnatomyFingerprint(const BiomechanicalLabelImageType * labels,
                         const bmr::Scene &                  scene,
                         const RegistrationSettings &        settings);

/** The distance maps of the scene's objective organs: of \a probabilities where given, else of \a labels
 * (interpolated between thick slices when \a interpolateSlices), exact within \a exactWithinMM of each organ
 * (ComputeSceneDistanceMaps()). */
std::map<std::string, Image<float, 3>::Pointer>
ObjectiveDistanceMaps(const BiomechanicalLabelImageType * labels,
                      const OrganProbabilityImages &      probabilities,
                      const bmr::Scene &                  scene,
                      double                              exactWithinMM,
                      bool                                interpolateSlices);

/** The analytic anatomy's labels at physical points (x, y, z triples) [mm]: the phantom's truth as a function. */
using AnatomyLabelsFunction = std::function<std::vector<std::int32_t>(const std::vector<double> &)>;

/** Each objective organ's volume fraction in every fixed voxel of \a labels, as a partial-volume segmentation would
 * give it: voxels whose 26 neighbours all carry their label are 0 or 1; the others are sampled at 4^3 sub-points,
 * each pulled back through the truth field \a field (trilinear between voxel centres) into the anatomy
 * (\a labelsAt). */
OrganProbabilityImages
FixedVolumeFractions(const bmr::Scene &                  scene,
                     const BiomechanicalLabelImageType * labels,
                     const BiomechanicalFieldType *      field,
                     const AnatomyLabelsFunction &       labelsAt);

/** Each objective organ's area fractions of its exact outlines on every fixed slice of \a labels, as an RTSTRUCT
 * drawn on the fixed scan carries them: the outlines traced on each slice's labels (marching squares, one vertex
 * per voxel edge the organ's boundary crosses), each vertex moved along its voxel edge onto the anatomy's boundary
 * by 12 bisections (1/4096 of a voxel) of the pulled-back anatomy, and the polygons' area fractions
 * (PlanarContourAreaFractions()). */
OrganProbabilityImages
FixedContourFractions(const bmr::Scene &                  scene,
                      const BiomechanicalLabelImageType * labels,
                      const BiomechanicalFieldType *      field,
                      const AnatomyLabelsFunction &       labelsAt);

/** The labels the moving anatomy is meshed from: \a labels interpolated between thick slices when \a settings
 * ask for it (RegistrationSettings::interpolateSlices), else \a labels themselves. */
BiomechanicalLabelImageType::ConstPointer
MeshedAnatomy(const BiomechanicalLabelImageType * labels, const RegistrationSettings & settings);

/** FEMElasticityOptimizer on \a setup with the distance maps \a maps; the curvature uncertainty only when
 * \a curvature; the observer (may be null) sees the inner solves. */
FEMElasticityOptimizer::Pointer
RunEstimation(const EstimationSetup &                                 setup,
              const std::map<std::string, Image<float, 3>::Pointer> & maps,
              bool                                                    curvature,
              PipelineObserver *                                      observer);

/** The resampled interval of every unknown modulus (ModulusInterval) by the settings' method, Bootstrap or
 * Rescan; failed resamples become warnings. */
std::map<std::string, ModulusInterval>
BootstrapModuli(const EstimationSetup &             setup,
                RegistrationResult &                r,
                const BiomechanicalLabelImageType * movingLabels,
                const BiomechanicalLabelImageType * fixedLabels,
                StageClock &                        clock);

/** The interval fit x/ exp(k s) of \a resamples [kPa] (ModulusInterval; k = \a halfWidths at 68 and 95 %, from
 * IntervalHalfWidths(); corrected for their offset when \a correctBias and it is significant); fewer than 3
 * resamples leave the whole search range. */
ModulusInterval
BootstrapInterval(double                        fit,
                  const std::vector<double> &   resamples,
                  const bmr::UnknownModulus &   unknown,
                  bool                          correctBias,
                  const std::array<double, 2> & halfWidths);

/** The interval fit x exp(+-z sigma) of the curvature's \a logSigma (infinite: the whole search range). */
ModulusInterval
CurvatureInterval(double fit, double logSigma, const bmr::UnknownModulus & unknown);

/** Withdraws \a interval's statement for \a reason: both ends not determined, the intervals the search range. */
void
DeclareNotDetermined(ModulusInterval & interval, const bmr::UnknownModulus & unknown, const std::string & reason);

/** Each scene label's volume in the moving and the fixed labels [mL] into r.labelVolumeML: what the scans show of
 * the organs' filling. */
void
MeasureLabelVolumes(RegistrationResult &                r,
                    const bmr::Scene &                  scene,
                    const BiomechanicalLabelImageType * movingLabels,
                    const BiomechanicalLabelImageType * fixedLabels);

} // namespace pipeline
} // namespace itk

#endif

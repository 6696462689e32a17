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
#ifndef itkBiomechanicalPipelines_h
#define itkBiomechanicalPipelines_h

#include "bmrElasticityEstimator.h"
#include "bmrLandmarks.h"
#include "bmrPhantom.h"
#include "bmrSimulation.h"
#include "itkImage.h"
#include "itkVector.h"

#include <array>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace itk {

// Whole jobs as one call, returning result structs (Doxygen group BiomechanicalRegistrationPipelines, docs/groups.dox):
// biomechreg parses, calls these, prints and writes; nothing else.

/** The image types of the pipelines: CT [HU], label maps, displacement fields [mm, LPS].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
using BiomechanicalCTImageType = Image<float, 3>;
using BiomechanicalLabelImageType = Image<std::int32_t, 3>;
using BiomechanicalFieldType = Image<Vector<double, 3>, 3>;

/** Receives what a pipeline is doing; every method does nothing by default.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
class BiomechanicalRegistration_EXPORT PipelineObserver
{
public:
  virtual ~PipelineObserver() = default;
  virtual void
  StageBegin(const std::string & /*stage*/)
  {}
  /** \a detail: a short result of the stage ("41043 tetrahedra, ..."), or empty. */
  virtual void
  StageEnd(const std::string & /*stage*/, double /*seconds*/, const std::string & /*detail*/)
  {}
  virtual void
  Warning(const std::string & /*message*/)
  {}
  /** After every inner solve of the estimation. */
  virtual void
  Iteration(const bmr::IterationRecord & /*record*/)
  {}
  /** Progress of the running stage: \a fraction of its work done, in [0, 1] (e.g. rescans finished of those
   * asked for), and what that is ("3 of 8 rescans"). Calls come one at a time, possibly from worker threads. */
  virtual void
  Progress(double /*fraction*/, const std::string & /*detail*/)
  {}
};

/** Wall time of one stage [s]. */
struct BiomechanicalRegistration_EXPORT PipelineStage
{
  std::string name;
  double      seconds{ 0.0 };
};

/** What SimulateLabelImage() made. \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT SimulationResult
{
  bmr::TetrahedralMesh            mesh;                  ///< with displacement [mm] and force [mN]
  bmr::ForwardSimulation          simulation;            ///< per-node and per-element fields of the solution
  BiomechanicalFieldType::Pointer pullBack;              ///< fixed -> moving [mm] on the reference grid
  BiomechanicalFieldType::Pointer push;                  ///< moving -> fixed [mm] on the moving grid (if asked for)
  SizeValueType                   invertedElements{ 0 }; ///< elements the displacement inverts
  std::vector<std::string>        warnings;
  std::vector<PipelineStage>      stages;
};

/** Meshes \a movingLabels for \a scene (CGAL Mesh_3), solves the scene's forward problem and computes the
 * pull-back field on \a reference's grid (and the push field on the moving grid when \a pushField).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT SimulationResult
SimulateLabelImage(const BiomechanicalLabelImageType * movingLabels,
                   const bmr::Scene &                  scene,
                   const ImageBase<3> *                reference,
                   PipelineObserver *                  observer = nullptr,
                   bool                                pushField = true);

/** As SimulateLabelImage() on a mesh already made for \a scene (its labels, sizes and excluded labels): the forward
 * problem and the fields, the push field on \a movingReference's grid. \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT SimulationResult
SimulateMesh(bmr::TetrahedralMesh mesh,
             const bmr::Scene &   scene,
             const ImageBase<3> * reference,
             const ImageBase<3> * movingReference,
             PipelineObserver *   observer = nullptr,
             bool                 pushField = true);

/** How RegisterSegmentedPair() states the uncertainty of the estimated moduli.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
enum class UncertaintyMethodEnum : std::uint8_t
{
  None,      ///< no interval
  Curvature, ///< the residual and the curvature of Phi* (fast; treats node residuals as independent noise)
  Bootstrap, ///< parametric bootstrap: resimulate from the estimate, revoxelize and re-estimate
  Rescan     ///< rescan the fixed anatomy at random sub-voxel shifts, re-mesh and re-estimate (default)
};

/** How the spread s of the resamples' log E becomes an interval's half-width k s.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
enum class IntervalQuantilesEnum : std::uint8_t
{
  /** Rescans: k from split-conformal calibration on pelvis phantoms (RescanCalibrations); the
   * bootstrap, which was not calibrated, falls back to Student. Default. */
  Calibrated,
  Student ///< k = t_(n-1) sqrt(1 + 1/n) at 68 % and 95 %: the resamples' log E taken as normal
};

/** Half-widths {k68, k95} of the rescans' intervals in units of their spread s, calibrated for a number of rescans:
 * the ceil(0.68 (m + 1))-th and ceil(0.95 (m + 1))-th smallest of m calibration scores |log Ehat - log E_true| / s
 * (split-conformal prediction: coverage >= 68 % and 95 % for a pair exchangeable with the calibration set). The
 * scores are the pelvis phantom pairs of two calibration runs on the default, converged truths, registered with the
 * default estimation mesh (surfaces refined: facet size and distance 0.85 x; benchmarks/results/
 * calibration_runs_facets085.csv and calibration_runs_facets085_fresh.csv, seeds 2044 and 2045; 1 mm voxels, moduli
 * log-uniform in 30-500 kPa), the pairs with no rescan on a search bound, s from each pair's 4 rescans. Checked on
 * 30 pairs not used here, drawn after the constants were committed (seed 2046,
 * calibration_runs_facets085_check2046.csv): 68 % coverage 0.73, 95 % 0.97 (docs/history/benchmarks.md).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct RescanCalibration
{
  unsigned int resamples;
  double       halfWidth68;
  double       halfWidth95;
};
/** 4 rescans (the default; 52 scores): Student's t_3 sqrt(5/4) would be 1.33 and 3.56. Other counts scale these by
 * Student's ratio (IntervalHalfWidths()); 8 rescans were not calibrated on this mesh. */
constexpr RescanCalibration RescanCalibrations[] = { { 4, 0.7826, 1.4996 } };

/** The interval at thick slices, where the rescans miss the truth (they resample the voxels' phase and the mesh; at
 * 2-3 mm slices the fit's error comes from the moving scan's slices: docs/history/benchmarks.md, "Clinical geometry").
 * Its calibration is the fit's own error, measured on pelvis phantom pairs whose two scans both have slices of sliceMM,
 * an in-plane spacing drawn from U(0.8, 1.2) mm, the fixed grid shifted by a random sub-voxel offset and moduli
 * log-uniform in 30-500 kPa (benchmarks/results/clinical_geometry/slice_calibration_fit.csv and the two earlier
 * checks' runs, slice_calibration_check_first_runs.csv and slice_calibration_check_runs.csv: 59, 20 and 83 pairs;
 * benchmarks/summarize_slice_calibration.py fit). The error grows with the modulus (stiff organs read too stiff by
 * more than soft ones), so the calibration is a line in log space, with \f$ E_0 = 100 \f$ kPa:
 * \f[ \log(\hat E / E_0) = a + \beta \log(E / E_0) + \varepsilon, \quad \varepsilon \sim N(0, s^2), \f]
 * fitted by the censored (Tobit) likelihood over all m pairs: a fit that stopped on the upper search bound says only
 * that it would have gone at least there. The statement inverts the line (classical calibration, so that it covers
 * every truth in the calibrated range at the stated rate, not only on average over the drawn moduli):
 * \f[ \tilde E = E_0 \exp\big((\log(\hat E / E_0) - a) / \beta\big), \quad
 *     I = E_0 \exp\big((\log(\hat E / E_0) - a \mp k s) / \beta\big), \quad k = t_{m-2} \sqrt{1 + 1/m} \f]
 * at 68 % and 95 % (Student's predictive factor for one more pair, with the line's two parameters). A fit on the
 * upper search bound U states the bound \f$ E \ge E_0 \exp((\log(U / E_0) - a - k s) / \beta) \f$: a smaller
 * truth would have stopped short of U but for an error beyond k s. The first calibration (a constant offset) over-
 * covered at 68 % and missed its error target at 3 mm; both are in docs/history/benchmarks.md ("Clinical geometry: an
 * interval calibrated per slice thickness"), with this line's check on pairs drawn after it was committed.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct SliceCalibration
{
  double       sliceMM;  ///< both scans' slice thickness
  double       offset;   ///< a: log(fit / E_0) of a truth of E_0 = SliceCalibrationReferenceKPa
  double       slope;    ///< beta
  double       logSigma; ///< s: the residual SD of log(fit) about the line
  unsigned int pairs;    ///< m, censored ones included
};
/** kPa: E_0 of the calibration line. */
constexpr double           SliceCalibrationReferenceKPa = 100.0;
constexpr SliceCalibration SliceCalibrations[] = { { 2.0, 0.3704, 1.3316, 0.2156, 59 },
                                                   { 2.5, 0.3179, 1.1708, 0.3310, 20 },
                                                   { 3.0, 0.2882, 1.1767, 0.3073, 83 } };
/** A scan's slices [mm] within this of a calibration's thickness use it. */
constexpr double SliceCalibrationToleranceMM = 0.25;
/** The in-plane voxel sides [mm] the calibrations drew, the only ones they hold for. */
constexpr double SliceCalibrationInPlaneMM[2] = { 0.8, 1.2 };

/** The calibration that holds for both scans' voxels, null when none does: both scans' in-plane sides (the two
 * smaller) within SliceCalibrationInPlaneMM and their slices (the largest side) within SliceCalibrationToleranceMM
 * of one calibration's thickness. A thick moving scan with a 1 mm fixed scan (or the reverse) is not calibrated:
 * the two lean opposite ways (docs/history/benchmarks.md, "which scan's slices make the 3 mm bias"). */
BiomechanicalRegistration_EXPORT const SliceCalibration *
FindSliceCalibration(const std::array<double, 3> & movingSpacing, const std::array<double, 3> & fixedSpacing);

/** Whether \a method states its intervals with the calibrated half-widths under \a quantiles (rescans only). */
BiomechanicalRegistration_EXPORT bool
UsesCalibratedHalfWidths(UncertaintyMethodEnum method, IntervalQuantilesEnum quantiles);

/** Half-widths {k68, k95} of the intervals, in units of the resamples' spread s, for \a resamples resamples of
 * \a method: Student's t_(n-1) sqrt(1 + 1/n), or the calibrated ones (rescans only): those of RescanCalibrations
 * for the largest calibrated count not above n (the smallest when n is below all), scaled by Student's ratio between
 * n and that count. Fewer than 3 resamples: infinite. */
BiomechanicalRegistration_EXPORT std::array<double, 2>
IntervalHalfWidths(UncertaintyMethodEnum method, IntervalQuantilesEnum quantiles, std::size_t resamples);

/** Mean and standard deviation of a normal sample of which some values are censored: those at or below
 * \a lowerLimit are known only to lie there or below, those at or above \a upperLimit only to lie there or above
 * (re-estimations stopped by a search bound). The maximum-likelihood estimate by expectation-maximization: each
 * censored value is replaced by its conditional moments under the current fit, \f$ E[x \mid x \ge c] = \mu +
 * \sigma \lambda(\alpha) \f$, \f$ \mathrm{Var}[x \mid x \ge c] = \sigma^2 (1 + \alpha \lambda - \lambda^2) \f$ with
 * \f$ \alpha = (c - \mu) / \sigma \f$, \f$ \lambda = \varphi(\alpha) / (1 - \Phi(\alpha)) \f$ (mirrored below), until
 * mu and sigma change by less than 1e-12 of sigma. Without censored values: the sample mean and the maximum-likelihood
 * (divide-by-n) deviation. Fewer than two distinct uncensored values determine no spread: sigma is then NaN.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct CensoredNormalFit
{
  double      mean{ 0.0 };
  double      sigma{ 0.0 };
  std::size_t censored{ 0 }; ///< values at or beyond a limit
};
BiomechanicalRegistration_EXPORT CensoredNormalFit
FitCensoredNormal(const std::vector<double> & values, double lowerLimit, double upperLimit);

/** Settings of the modulus uncertainty (the rescans or the parametric bootstrap of ModulusInterval).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT UncertaintySettings
{
  UncertaintyMethodEnum method{ UncertaintyMethodEnum::Rescan };
  /** Re-estimations (rescan, bootstrap). 4 by default, which run in about half the time of 8; 8 (also calibrated,
   * RescanCalibrations) give intervals about a third narrower in log E (docs/history/benchmarks.md). */
  unsigned int  resamples{ 4 };
  std::uint64_t seed{ 1 }; ///< the resamples' random numbers: same seed, same interval
  /** Resamples run at once; 0 (default): ITK's global default number of threads (`--threads`). Each resample
   * holds its own meshes and factorization (about 280 MB on the 1 mm pelvis). With one unknown modulus the
   * intervals are bit-identical whatever the number (biomechreg_determinism); with two or more, vnl's
   * L-BFGS-B (static state, ITK issue #230) is serialized and the intervals agree to rounding. */
  unsigned int threads{ 0 };
  double       simulationMeshScale{ 0.8 };    ///< resimulation mesh sizes relative to the estimation's
  double       meshJitter{ 0.15 };            ///< each resample re-meshes at the sizes x U(1 - this, 1 + this)
  double       shiftVoxels{ 0.5 };            ///< sub-voxel shift of the revoxelized grid, uniform in +-
  double       rotationDegrees{ 2.0 };        ///< its rotation, uniform in [0, this] about a random axis
  double       tangentialWallFraction{ 0.3 }; ///< tangential wall motion / the wall's own motion
  /** Gaussian sigma [voxels] that turns the rescanned (or revoxelized) labels into a smooth anatomy. */
  double smoothingVoxels{ 0.5 };
  /** Centre the interval on fit e^(-b) when the resamples' offset b is significant (BootstrapBiasSignificance).
   * Off by default: on the pelvis phantoms b came from the mesh jitter (the default mesh sits near a minimum of
   * the mesh dependence), and correcting by it made the estimate worse in both calibration runs. */
  bool correctBias{ false };
  /** Each resample's outer search starts at the fit with the fit's curvature, without the sweep and its coarse
   * mesh (on by default; off: each resample sweeps as the fit did). */
  bool warmStart{ true };
  /** Each resample's outer search over log E stops when its next step would be shorter than this (one unknown
   * modulus). The estimate's own search resolves 1e-3; a resample needs only a fraction of the resamples'
   * spread (sigma of log E 0.04-0.1 on the pelvis phantoms), and every step saved is a factorization. */
  double stepTolerance{ 0.01 };
  /** Half-widths from the calibration (default, rescans) or Student's t (IntervalQuantilesEnum). */
  IntervalQuantilesEnum quantiles{ IntervalQuantilesEnum::Calibrated };
  /** The largest label voxel side [mm] at which a modulus is stated from the resamples (default
   * bmr::StatedModulusVoxelLimitMM, where their coverage was shown). Above it the interval is the thick slices'
   * calibration where one holds (FindSliceCalibration()), else the modulus is reported as not determined; no
   * resample is computed either way. A study
   * that measures coverage at coarser voxels (benchmarks/run_calibration_benchmark.sh) raises it; the run then
   * warns that the interval is stated where its coverage was not shown. */
  double statedVoxelLimitMM{ bmr::StatedModulusVoxelLimitMM };
};

/** Standard errors of the resamples' median beyond which ModulusInterval corrects the fit for the bias b
 * (UncertaintySettings::correctBias). */
constexpr double BootstrapBiasSignificance = 3.0;

/** The interval of one estimated modulus [kPa], from n re-estimations on the moving labels meshed again at
 * randomly scaled sizes (the estimate depends on the mesh by several per cent, not monotonically: that is part
 * of its uncertainty) of resampled data:
 * - Rescan (default): the fixed anatomy itself, a smooth volume-preserving function of its labels (or its
 *   probabilities), revoxelized on the fixed grid shifted by a random sub-voxel offset and rotated by a small
 *   random angle: another scan of the same anatomy, with no model in the loop;
 * - Bootstrap (the dissertation's generative model run forward from the estimate): the fixed anatomy
 *   resimulated from the estimate on a finer, independent mesh with the estimated wall motion plus a smooth
 *   random tangential part (what walls along normals cannot see), revoxelized in the same way. Its resamples
 *   drift off the fit on the pelvis phantoms (docs/estimation.md), hence not the default.
 *
 * With \f$ \ell_k = \log E^*_k \f$ of the resamples: \f[ b = \mathrm{median}_k \ell_k - \log \hat E, \quad s =
 * \mathrm{SD}_k \ell_k, \quad \log \tilde E = \log \hat E \; (- b \text{ if asked and } |b| > 3 \cdot 1.2533\, s /
 * \sqrt n), \quad I_{1-\alpha} = \tilde E \exp(\pm k_{1-\alpha} s) \f] (centred on the fit;
 * corrected for the resamples' offset b only when asked and when it exceeds three standard errors of their median;
 * k from IntervalHalfWidths(): calibrated on phantoms for the rescans, else \f$ t_{1-\alpha/2,n-1} \sqrt{1+1/n} \f$).
 * An interval end beyond the scene's bounds is not determined by the images: the modulus is then reported as a bound
 * ("E >= lower end"). Resamples on a search bound stopped there: they only say "at least" (or "at most") the bound,
 * and their SD understates the spread. Then s is the larger of the SD and the censored maximum-likelihood sigma
 * (FitCensoredNormal(), times sqrt(n / (n - 1)) to compare with the SD), which widens the bound's determined end. */
struct BiomechanicalRegistration_EXPORT ModulusInterval
{
  double                fit{ 0.0 };                 ///< kPa: the estimate of the fit (the state and fields use it)
  double                estimate{ 0.0 };            ///< kPa: the fit, bias-corrected when biasCorrected
  double                logBias{ 0.0 };             ///< b
  bool                  biasCorrected{ false };     ///< true: asked, |b| significant, estimate = fit e^(-b)
  double                logSigma{ 0.0 };            ///< s (bootstrap) or the curvature's sigma
  std::array<double, 2> interval68{ { 0.0, 0.0 } }; ///< kPa
  std::array<double, 2> interval95{ { 0.0, 0.0 } }; ///< kPa
  bool                  lowerDetermined{ true };    ///< false: the images do not bound E from below
  bool                  upperDetermined{ true };    ///< false: only "at least interval95[0]"
  std::size_t           censoredResamples{ 0 };     ///< resamples on a search bound (their spread: censored fit)
  std::vector<double>   resampleModuli;             ///< kPa, in resample order
  std::string           method;                     ///< "rescan", "bootstrap", "curvature"
  std::string           quantiles;                  ///< "calibrated", "student" or "normal" (curvature)
  /** Why no modulus is stated although the search found a fit (for example label voxels coarser than
   * bmr::StatedModulusVoxelLimitMM); empty when the interval stands. Non-empty: both ends not determined. */
  std::string notDeterminedReason;
  double      calibratedSliceMM{ 0.0 }; ///< mm: the SliceCalibration used (method "slice-calibration"), else 0
};

/** One line stating the modulus of \a name: "E = 92.1 kPa (68 %: 80.3-105.6 kPa, 95 %: ...)" when both ends are
 * determined, "E >= 220 kPa (95 %), the upper end not determined by the images" when the interval reaches the
 * upper search bound (likewise "E <= " for the lower one), "not determined by the images" when both.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT std::string
                                 ModulusIntervalText(const std::string & name, const ModulusInterval & interval);

/** The interval of \a fit [kPa] at thick slices from \a calibration (SliceCalibration: the calibration line
 * inverted, Student's predictive half-widths t_(m-2) sqrt(1 + 1/m) s); an end beyond \a unknown's search range is not
 * determined, as for every interval. A fit on the upper search bound states a lower bound (E >= the line's inverse of
 * the bound less k s), a fit on the lower one an upper bound; logBias is log(fit / estimate) at this fit and logSigma
 * s / beta, the interval's half-width per unit of k in log E.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT ModulusInterval
SliceCalibratedInterval(double fit, const SliceCalibration & calibration, const bmr::UnknownModulus & unknown);

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

/** Per organ (scene label name), a probability or partial-volume image of the fixed scan, in [0, 1].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
using BiomechanicalProbabilityImageType = Image<float, 3>;
using OrganProbabilityImages = std::map<std::string, BiomechanicalProbabilityImageType::Pointer>;

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

/** Settings of the Demons baseline (itk::DemonsBaselineRegistrationFilter); the defaults are biomechreg's.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct BiomechanicalRegistration_EXPORT DemonsSettings
{
  std::string  variant{ "diffeomorphic" }; ///< or "symmetric" (fast symmetric forces)
  unsigned int levels{ 3 };
  unsigned int iterations{ 50 }; ///< per level
  double       sigma{ 1.5 };     ///< field smoothing [voxels]
  bool         histogramMatching{ true };
};

/** Demons of the moving CT onto the fixed CT; returns the fixed -> moving field [mm]. The label images are used
 * only when \a flatten names organs to flatten (each replaced by its mean in its own image). The \a observer
 * (may be null) hears the progress over the levels.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT BiomechanicalFieldType::Pointer
                                 RunDemonsBaseline(const BiomechanicalCTImageType *    fixedCT,
                                                   const BiomechanicalCTImageType *    movingCT,
                                                   const BiomechanicalLabelImageType * fixedLabels,
                                                   const BiomechanicalLabelImageType * movingLabels,
                                                   const std::vector<std::int32_t> &   flatten,
                                                   const DemonsSettings &              settings,
                                                   PipelineObserver *                  observer = nullptr);

/** \a scene with every mesh size (cell, facet, facet distance, per-label cell sizes, the local refinement's size but
 * not its distance) multiplied by \a factor. */
BiomechanicalRegistration_EXPORT bmr::Scene
                                 ScaledMeshSizes(bmr::Scene scene, double factor);

} // namespace itk

#endif

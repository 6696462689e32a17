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
#ifndef itkModulusInterval_h
#define itkModulusInterval_h

#include "bmrElasticityEstimator.h"
#include "itkPipelineTypes.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace itk {

// The stated interval of an estimated modulus: its methods, calibrations and text.

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
 * an in-plane spacing drawn from U(0.8, 1.2) mm, the fixed grid shifted by a random sub-voxel offset, moduli
 * log-uniform in 30-500 kPa and bladder wall motions in 3-10 mm (benchmarks/results/clinical_geometry/, the
 * slice_calibration_*_runs.csv listed in docs/method.md; benchmarks/summarize_slice_calibration.py fit --filling).
 * The fit's error grows with the modulus (stiff organs read too stiff by more than soft ones) and depends on how much
 * the bladder filled between the scans, its volume change dV (fixed minus moving labels, mL: what the scans show of
 * the load); its spread grows with the modulus and shrinks with the filling (a stiff organ that barely deforms says
 * little about its stiffness). So the calibration is a line in log space with a residual SD of its own, with
 * \f$ E_0 = 100 \f$ kPa, \f$ x = \log(E / E_0) \f$ and \f$ z = \Delta V - V_0 \f$:
 * \f[ \log(\hat E / E_0) \sim N\big(\mu(x), \sigma(x)^2\big), \quad \mu(x) = a + \beta x + \gamma z, \quad
 *     \sigma(x) = s \exp(c x + d z), \f]
 * fitted by the censored (Tobit) likelihood over all m pairs: a fit that stopped on the upper search bound says only
 * that it would have gone at least there. The statement inverts the calibration (classical calibration, so that it
 * covers every truth in the calibrated range at the stated rate, not only on average over the drawn moduli): the
 * estimate is the truth whose line passes through the fit, \f$ \tilde x = (\log(\hat E / E_0) - a - \gamma z) /
 * \beta \f$, and the interval every truth the fit is consistent with,
 * \f[ I = \{ E : |\log(\hat E / E_0) - \mu(x)| \le k \sigma(x) \}, \quad k = t_{m-p} \sqrt{1 + 1/m} \f]
 * at 68 % and 95 % (Student's predictive factor for one more pair, with the calibration's p parameters). Where the
 * spread grows faster than the line (stiff organs at little filling) no truth above some modulus is excluded: the
 * upper end is then not determined. A fit on the upper search bound states a lower bound. A volume change outside
 * the calibrated range states no modulus (not determined, with the reason). The earlier calibrations (a constant
 * offset; a line with one spread) over-covered at 68 % at 3 mm; both are in docs/history/benchmarks.md ("Clinical
 * geometry"), with this one's check on pairs drawn after it was committed.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
struct SliceCalibration
{
  double sliceMM;            ///< both scans' slice thickness
  double offset;             ///< a: log(fit / E_0) of a truth of E_0 = SliceCalibrationReferenceKPa at V_0
  double slope;              ///< beta
  double fillingSlope;       ///< gamma [1/mL]: log(fit) per mL of the filling organ's volume change about V_0
  double logSigma;           ///< s: the residual SD of log(fit) at E_0 and V_0
  double sigmaSlope;         ///< c: log of the residual SD per unit log(E / E_0)
  double sigmaFillingSlope;  ///< d [1/mL]: log of the residual SD per mL of volume change
  double fillingReferenceML; ///< V_0 [mL]
  /** The volume changes [mL] the calibration pairs spanned, the only ones it holds for (when gamma or d is not 0). */
  double       fillingRangeML[2];
  unsigned int pairs; ///< m, censored ones included
};
/** kPa: E_0 of the calibration line. */
constexpr double SliceCalibrationReferenceKPa = 100.0;
/** The scene label whose volume change between the scans is the calibration's filling term. */
constexpr const char * SliceCalibrationFillingOrgan = "bladder";
/** The shipped calibrations, one per slice thickness (benchmarks/summarize_slice_calibration.py fit --filling on the
 * runs docs/method.md lists). */
constexpr SliceCalibration SliceCalibrations[] = {
  { 2.0, 0.3575, 1.2796, 0.002616, 0.1812, 0.7332, -0.003984, 76.0, { 33.0, 118.0 }, 139 },
  { 2.5, 0.1758, 1.1578, 0.003280, 0.2721, 0.7327, -0.009878, 76.0, { 33.0, 119.0 }, 120 },
  { 3.0, 0.3285, 1.1877, 0.001671, 0.2384, 0.5187, -0.005208, 76.0, { 33.0, 119.0 }, 155 }
};
/** The two-sided level whose lower end a thick-slice bound states. Where the upper end is not determined the 95 %
 * statement is a bound, "E >= L", and bounds arise only for stiff organs, where the fits are censored at the
 * search bound and the normal model's upper tail is the least supported (the calibration pairs' standardized
 * residuals at 130-220 kPa reach 2.7, and 3.0 on the bound, more often than a normal tail has them). A false bound
 * tells a user an organ is stiff when it is not, with no upper end to temper it, so L is the lower end at this
 * stricter level: still a 95 % statement (it holds at least as often), the interval's other ends unchanged. */
constexpr double SliceCalibrationBoundLevel = 0.999;
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

  /** Throws itk::InvalidArgumentError naming the first setting out of its range: at least 3 resamples for rescans
   * or the bootstrap, meshJitter in [0, 0.9), the other scales finite and >= 0, simulationMeshScale in [0.25, 2],
   * statedVoxelLimitMM > 0. */
  void
  Validate() const;
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

/** The interval of \a fit [kPa] at thick slices from \a calibration (SliceCalibration: the calibration inverted,
 * Student's predictive half-widths t_(m-p) sqrt(1 + 1/m) sigma(x)) at the filling organ's volume change
 * \a fillingChangeML between the scans (fixed minus moving labels, mL; NaN: not measured). An end beyond
 * \a unknown's search range is not determined, as for every interval. A fit on the upper search bound states a lower
 * bound, a fit on the lower one an upper bound. A calibration with a filling term states no modulus (not determined,
 * with the reason) when \a fillingChangeML is NaN or outside its fillingRangeML. logBias is log(fit / estimate) and
 * logSigma sigma / beta at the estimate, the interval's half-width per unit of k in log E there.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT ModulusInterval
SliceCalibratedInterval(double                      fit,
                        const SliceCalibration &    calibration,
                        const bmr::UnknownModulus & unknown,
                        double                      fillingChangeML);

} // namespace itk

#endif

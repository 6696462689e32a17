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
#ifndef itkPhantomCohort_h
#define itkPhantomCohort_h

#include "itkBiomechanicalPipelines.h"

#include "bmrStatistics.h"

namespace itk {

/** \brief How a phantom cohort is drawn (biomechreg phantom-cohort): N patients, each with its own anatomy,
 * T-stage and prostate modulus, and M daily fractions with random fillings.
 *
 * Patient p (1-based) draws from std::mt19937_64(seed * 1000 + p), so adding patients does not change the
 * earlier ones:
 * - T-stage uniform over \c stages (default T1 ... T3, as in the dissertation's cohort);
 * - prostate modulus log-normal: E = stageMedianE[stage - 1] exp(logSpread z), z standard normal (Box-Muller on
 *   the raw integers), rounded to whole kPa; the defaults 40, 60, 90 kPa with a spread of 0.15 give each stage its
 *   own range that overlaps its neighbours, as a cohort would;
 * - anatomy (bmr::PelvisAnatomy): prostate scale U(0.85, 1.2) (volume 0.6 ... 1.7 times the default 24 ml),
 *   bladder scale U(0.85, 1.1), rectum radius U(11, 14) mm, offset of the organs U(-3, 3) mm per axis; drawn again
 *   (up to 50 times) until the organs keep 3 mm from each other and 5 mm from the bones and the body outline
 *   (bmr::MeasurePelvisClearance);
 * - fraction f: bladder filling U(bladderMM), rectum U(rectumMM) [mm], CT noise and grid shift seeded by
 *   (seed * 1000 + p) * 100 + f; the planning scan seeded by the patient, the same for all its fractions. */
struct BiomechanicalRegistration_EXPORT PhantomCohortSettings
{
  unsigned int          patients{ 10 };
  unsigned int          fractions{ 6 };
  std::uint64_t         seed{ 1 };
  std::array<int, 2>    stages{ { 1, 3 } };                  ///< the T-stages drawn, inclusive
  std::array<double, 4> stageMedianE{ { 40, 60, 90, 130 } }; ///< kPa, for T1 ... T4
  double                logSpread{ 0.15 };
  std::array<double, 2> bladderMM{ { 2.0, 8.0 } };
  std::array<double, 2> rectumMM{ { 1.0, 5.0 } };
  PhantomSettings       base; ///< grid, noise, model, truth mesh of every pair
};

/** One phantom patient: its truth and the settings of each of its fractions' pairs. */
struct BiomechanicalRegistration_EXPORT PhantomCohortPatient
{
  std::string                  name; ///< P01, P02, ...
  int                          stage{ 1 };
  double                       prostateE{ 0.0 }; ///< kPa
  bmr::PelvisAnatomy           anatomy;
  bmr::PelvisClearance         clearance;
  std::vector<PhantomSettings> fractions;
};

/** Draws the cohort; throws itk::ExceptionObject on settings out of range or an anatomy that cannot be drawn. */
BiomechanicalRegistration_EXPORT std::vector<PhantomCohortPatient>
                                 DrawPhantomCohort(const PhantomCohortSettings & settings);

/** The truth's correlation of the prostate modulus with the T-stage over the patients (Pearson, Spearman, Kendall
 * tau-b), as the cohort study computes the recovered one; empty below 3 patients. */
BiomechanicalRegistration_EXPORT std::vector<bmr::CorrelationTestResult>
                                 PhantomCohortTruthCorrelations(const std::vector<PhantomCohortPatient> & cohort);

/** Makes every pair of \a cohort (MakePhantomPair) and writes it under \a directory: per patient P the planning
 * scan, labels, scene and seeds (P/planning_ct.nrrd, planning_labels.nrrd, scene.json, seeds_planning.csv), per
 * fraction F the daily scan, labels, seeds and truth (P/F/daily_ct.nrrd, daily_labels.nrrd, seeds_daily.csv,
 * truth.json); then cohort.csv (the file biomechreg cohort reads), truth.csv (stage, modulus [kPa], anatomy and
 * clearances [mm] per patient), truth_fractions.csv (fillings [mm], seeds) and truth_correlations.csv. A patient's
 * fractions share one planning anatomy, so its truth is meshed once and reused. Every file is written atomically.
 * \ingroup BiomechanicalRegistrationPipelines */
BiomechanicalRegistration_EXPORT void
WritePhantomCohort(const std::string &                       directory,
                   const std::vector<PhantomCohortPatient> & cohort,
                   PipelineObserver *                        observer = nullptr);

} // namespace itk

#endif

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
#ifndef bmrCohortStudy_h
#define bmrCohortStudy_h

#include "bmrCohort.h"
#include "bmrStatistics.h"

#include <array>
#include <limits>

namespace bmr {

/** What one fraction's registration reported (report.json of biomechreg register), or that it is missing. */
struct BiomechanicalRegistration_EXPORT CohortFractionResult
{
  std::size_t                                  fraction{ 0 }; ///< index in Cohort::fractions
  bool                                         available{ false };
  std::string                                  reportPath, logPath;
  std::map<std::string, double>                modulus;    ///< kPa, per unknown material: the interval's estimate
  std::map<std::string, std::array<double, 2>> interval68; ///< kPa, when the report has an interval
  std::map<std::string, bool>                  determined; ///< both ends of that interval determined by the data
  bool                                         identifiable{ true };
  std::size_t                                  warnings{ 0 };
  double                                       wallTime{ std::numeric_limits<double>::quiet_NaN() }; ///< s
};

/** One patient's recovered modulus of one material over its available fractions. */
struct BiomechanicalRegistration_EXPORT CohortPatientModulus
{
  std::string       patient, material;
  SummaryStatistics modulus;      ///< kPa; count 0 when no fraction is available
  std::size_t       missing{ 0 }; ///< fractions without a report
  std::size_t       undetermined{
    0
  }; ///< fractions whose interval has an end the data do not determine, or with no modulus stated
  double meanIntervalWidth{ 0 }; ///< mean width of the 68 % intervals [kPa], 0 without intervals
};

/** The correlation of the per-patient mean modulus of \c material with a covariate, over the patients with at
 * least one available fraction. */
struct BiomechanicalRegistration_EXPORT CohortCorrelation
{
  std::string                        material, covariate;
  std::vector<CorrelationTestResult> tests; ///< Pearson, Spearman, Kendall tau-b; empty when not computable
  std::string                        note;  ///< why it is not computable (fewer than 3 patients, constant values)
};

/** \brief The statistics of a cohort's registrations (dissertation section 3.3.2, Table 3.2 and Fig. 3.9).
 *
 * Per patient n, mean, sample SD and median of each recovered modulus; per material and covariate Pearson's r
 * and Spearman's rho with the two-sided p of the t approximation, Kendall's tau-b with its normal approximation,
 * and the exact permutation p when there are at most 10 patients. A fraction without a report (failed, or not
 * run yet) is listed as missing with its log and leaves the others' statistics intact. */
struct BiomechanicalRegistration_EXPORT CohortStudy
{
  Cohort                            cohort;
  std::string                       directory; ///< holds results/<patient>/<fraction>/report.json and logs/
  std::vector<std::string>          materials; ///< the unknown materials the reports recovered, sorted
  std::vector<CohortFractionResult> fractions; ///< in the cohort's order
  std::vector<CohortPatientModulus> patients;  ///< per patient (cohort order), then per material
  std::vector<CohortCorrelation>    correlations;

  /** Reads every fraction's report under \a studyDirectory and computes the statistics; throws
   * itk::ExceptionObject naming a report that exists but cannot be read. */
  static CohortStudy
  Summarize(const Cohort & cohort, const std::string & studyDirectory);

  std::size_t
  NumberOfMissingFractions() const;
  /** fraction,patient,<covariates>,status,<material>_kPa,<material>_68_low_kPa,..,wall_time_s,report,log */
  std::string
  FractionsCsv() const;
  /** patient,<covariates>,material,n,missing,mean_kPa,sd_kPa,median_kPa,min_kPa,max_kPa,undetermined,... */
  std::string
  PatientsCsv() const;
  /** material,covariate,n,method,coefficient,statistic,p_approximate,p_permutation,permutation_exact */
  std::string
  CorrelationsCsv() const;
  /** The report: the patients' table (as Table 3.2), the correlations, the missing fractions with their logs. */
  std::string
  ReportMarkdown() const;
};

/** Where the workflow keeps a fraction's report and log, relative to the study directory. */
BiomechanicalRegistration_EXPORT std::string
                                 CohortReportPath(const CohortFraction & fraction);
BiomechanicalRegistration_EXPORT std::string
                                 CohortLogPath(const CohortFraction & fraction);

} // namespace bmr

#endif

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
#ifndef bmrCohort_h
#define bmrCohort_h

#include "BiomechanicalRegistrationExport.h"

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace bmr {

/** One daily image of a cohort and the planning scan it is registered from (paths resolved against the
 * cohort file's directory). */
struct BiomechanicalRegistration_EXPORT CohortFraction
{
  std::string patient;
  std::string fraction;
  std::string planningCT, planningLabels;
  std::string dailyCT, dailyLabels;
  std::string scene;
  std::size_t line{ 0 }; ///< in the cohort file
  /** "patient/fraction": the job's name and its folder under the results. */
  std::string
  Key() const
  {
    return patient + "/" + fraction;
  }
};

/** A patient: its covariates (one value per covariate column, the same on each of its rows) and the indices of
 * its fractions in Cohort::fractions. */
struct BiomechanicalRegistration_EXPORT CohortPatient
{
  std::string                   name;
  std::map<std::string, double> covariates;
  std::vector<std::size_t>      fractions;
};

/** \brief A cohort description (dissertation section 3.3.2: patients, each with a planning scan, daily scans
 * and clinical covariates such as the T-stage).
 *
 * The file is a CSV (bmr::CsvTable: '#' comments, no quoting) with the columns
 * - patient, fraction: names of letters, digits, '_', '-' and '.', the pair (patient, fraction) unique;
 * - planning_ct, planning_labels, daily_ct, daily_labels, scene: paths relative to the file or absolute, each
 *   an existing file;
 * - planning_landmarks and daily_landmarks are refused: a fraction seen only through its markers recovers no
 *   modulus (biomechreg markers / itk::EstimateTreatmentFromMarkers carries the anatomy with known moduli);
 * - every other column a covariate of the patient: a number, or a clinical T-stage written T0 ... T4 with an
 *   optional sub-stage letter (T2b), read as its number 0 ... 4 as the dissertation codes T1, T2, T3 as 1, 2, 3
 *   (sub-stages are not ordered finer because their definitions differ between editions of the TNM system).
 *   TX ("cannot be assessed") and empty values are refused; a patient's covariate must be the same on all of
 *   its rows.
 *
 * Every error names the file, the line and the column. */
struct BiomechanicalRegistration_EXPORT Cohort
{
  std::string                 path;
  std::vector<std::string>    covariateNames; ///< in file order
  std::vector<CohortFraction> fractions;      ///< in file order
  std::vector<CohortPatient>  patients;       ///< in order of first appearance

  /** Reads and checks \a cohortPath (see the class description); throws itk::ExceptionObject. */
  static Cohort
  Read(const std::string & cohortPath);

  /** The patient called \a name; throws naming the cohort when there is none. */
  const CohortPatient &
  Patient(const std::string & name) const;
};

/** A covariate's value: a decimal number, or a T-stage (T0 ... T4, optional letter a-c) as its number. Returns
 * false for anything else, TX included. */
BiomechanicalRegistration_EXPORT bool
ParseCovariate(const std::string & text, double & value);

/** How the cohort workflow (workflows/cohort/Snakefile) runs each fraction's registration. */
struct BiomechanicalRegistration_EXPORT CohortWorkflowSettings
{
  std::string              executable;      ///< biomechreg, absolute
  std::vector<std::string> registerOptions; ///< passed to every biomechreg register (default: --outputs report)
  unsigned int             threadsPerJob{ 1 };
  /** Per job, for a cluster's scheduler: the largest peak resident memory measured for one registration with the
   * default rescan interval on a 1 mm pelvis of 200 x 160 x 160 voxels (docs/history/benchmarks.md, the side-by-side
   * runs), plus about a quarter: a job the scheduler kills for its memory costs more than an idle reservation. */
  unsigned int memoryMB{ 2000 };
  unsigned int runtimeMinutes{ 30 }; ///< per job, for a cluster's scheduler
};

/** The workflow's configuration (JSON): the cohort, the settings and one job per fraction, keyed
 * "patient/fraction", with its absolute input paths. */
BiomechanicalRegistration_EXPORT std::string
CohortWorkflowConfigJson(const Cohort & cohort, const CohortWorkflowSettings & settings);

/** The columns of a cohort file that are not covariates. */
BiomechanicalRegistration_EXPORT const std::vector<std::string> &
                                       CohortFileColumns();

} // namespace bmr

#endif

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
#include "bmrCohortStudy.h"

#include "bmrError.h"
#include "bmrScene.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <set>
#include <sstream>

namespace bmr {
namespace {

using Json = nlohmann::json;
constexpr const char * Where = "bmr::CohortStudy";

std::string
Number(double value, int precision = 6)
{
  if (!std::isfinite(value))
  {
    return "";
  }
  std::ostringstream o;
  o << std::setprecision(precision) << value;
  return o.str();
}

std::string
Fixed(double value, int digits)
{
  if (!std::isfinite(value))
  {
    return "–";
  }
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << value;
  return o.str();
}

/** The recovered moduli of \a materials as \a report states them. */
void
ReadReport(const Json & report, const std::vector<std::string> & materials, CohortFractionResult & r)
{
  const Json & intervals = report.value("youngs_modulus_interval", Json::object());
  for (const auto & m : materials)
  {
    if (intervals.contains(m))
    {
      const Json & i = intervals.at(m);
      if (!i.value("not_determined_reason", std::string()).empty())
      {
        r.determined[m] = false; // no modulus stated (e.g. from thick slices): not a value of the cohort
        continue;
      }
      r.modulus[m] = i.at("estimate_kPa").get<double>();
      r.interval68[m] = { { i.at("interval_68_kPa").at(0).get<double>(),
                            i.at("interval_68_kPa").at(1).get<double>() } };
      r.determined[m] = i.at("lower_end_determined").get<bool>() && i.at("upper_end_determined").get<bool>();
    }
    else
    {
      r.modulus[m] = report.at("youngs_modulus_kPa").at(m).get<double>();
    }
  }
  r.identifiable = report.value("identifiable", true);
  r.warnings = report.value("warnings", Json::array()).size();
  r.wallTime = report.at("wall_time_s").at("total").get<double>();
}

CohortFractionResult
ReadFractionResult(const CohortFraction & f, std::size_t index, const std::string & directory)
{
  CohortFractionResult r;
  r.fraction = index;
  r.reportPath = directory + "/" + CohortReportPath(f);
  r.logPath = directory + "/" + CohortLogPath(f);
  std::ifstream in(r.reportPath);
  if (!in)
  {
    return r;
  }
  std::vector<std::string> materials;
  for (const SceneLabel * l : ReadScene(f.scene).UnknownLabels())
  {
    materials.push_back(l->name);
  }
  try
  {
    ReadReport(Json::parse(in), materials, r);
  }
  catch (const Json::exception & e)
  {
    Fail(Where, "the report \"" + r.reportPath + "\" of " + f.Key() + " cannot be read: " + e.what());
  }
  r.available = true;
  return r;
}

CohortPatientModulus
SummarizePatient(const CohortStudy & study, const CohortPatient & patient, const std::string & material)
{
  CohortPatientModulus s;
  s.patient = patient.name;
  s.material = material;
  std::vector<double> values;
  double              widths = 0.0;
  std::size_t         intervals = 0;
  for (std::size_t k : patient.fractions)
  {
    const CohortFractionResult & r = study.fractions[k];
    if (r.available && !r.modulus.count(material) && r.determined.count(material))
    {
      ++s.undetermined; // registered, but no modulus stated
      continue;
    }
    if (!r.available || !r.modulus.count(material))
    {
      ++s.missing;
      continue;
    }
    values.push_back(r.modulus.at(material));
    if (r.interval68.count(material))
    {
      widths += r.interval68.at(material)[1] - r.interval68.at(material)[0];
      ++intervals;
      s.undetermined += r.determined.at(material) ? 0 : 1;
    }
  }
  if (!values.empty())
  {
    s.modulus = Summarize(values);
  }
  s.meanIntervalWidth = intervals > 0 ? widths / double(intervals) : 0.0;
  return s;
}

bool
IsConstant(const std::vector<double> & v)
{
  return std::all_of(v.begin(), v.end(), [&v](double x) { return x == v.front(); });
}

CohortCorrelation
Correlate(const CohortStudy & study, const std::string & material, const std::string & covariate)
{
  CohortCorrelation c;
  c.material = material;
  c.covariate = covariate;
  std::vector<double> x, y;
  for (const CohortPatient & patient : study.cohort.patients)
  {
    for (const CohortPatientModulus & m : study.patients)
    {
      if (m.patient == patient.name && m.material == material && m.modulus.count > 0)
      {
        x.push_back(patient.covariates.at(covariate));
        y.push_back(m.modulus.mean);
      }
    }
  }
  if (x.size() < 3)
  {
    c.note = std::to_string(x.size()) + " patient(s) with a result: a correlation needs at least 3";
  }
  else if (IsConstant(x) || IsConstant(y))
  {
    c.note = std::string("the ") + (IsConstant(x) ? covariate : "mean " + material + " modulus") +
             " is the same for every patient: no correlation is defined";
  }
  else
  {
    for (CorrelationEnum method : { CorrelationEnum::Pearson, CorrelationEnum::Spearman, CorrelationEnum::KendallTauB })
    {
      c.tests.push_back(CorrelationTest(x, y, method));
    }
  }
  return c;
}

} // namespace

std::string
CohortReportPath(const CohortFraction & fraction)
{
  return "results/" + fraction.Key() + "/report.json";
}

std::string
CohortLogPath(const CohortFraction & fraction)
{
  return "logs/" + fraction.Key() + ".log";
}

CohortStudy
CohortStudy::Summarize(const Cohort & cohort, const std::string & studyDirectory)
{
  CohortStudy study;
  study.cohort = cohort;
  study.directory = studyDirectory;
  std::set<std::string> materials;
  for (std::size_t k = 0; k < cohort.fractions.size(); ++k)
  {
    study.fractions.push_back(ReadFractionResult(cohort.fractions[k], k, studyDirectory));
    for (const auto & kv : study.fractions.back().modulus)
    {
      materials.insert(kv.first);
    }
  }
  study.materials.assign(materials.begin(), materials.end());
  for (const CohortPatient & patient : cohort.patients)
  {
    for (const auto & material : study.materials)
    {
      study.patients.push_back(SummarizePatient(study, patient, material));
    }
  }
  for (const auto & material : study.materials)
  {
    for (const auto & covariate : cohort.covariateNames)
    {
      study.correlations.push_back(Correlate(study, material, covariate));
    }
  }
  return study;
}

std::size_t
CohortStudy::NumberOfMissingFractions() const
{
  return static_cast<std::size_t>(
    std::count_if(fractions.begin(), fractions.end(), [](const CohortFractionResult & r) { return !r.available; }));
}

std::string
CohortStudy::FractionsCsv() const
{
  std::ostringstream o;
  o << "# one row per daily image; moduli in kPa, wall time in s\nfraction,patient";
  for (const auto & c : cohort.covariateNames)
  {
    o << "," << c;
  }
  o << ",status";
  for (const auto & m : materials)
  {
    o << "," << m << "_kPa," << m << "_68_low_kPa," << m << "_68_high_kPa," << m << "_determined";
  }
  o << ",identifiable,warnings,wall_time_s,report,log\n";
  for (const CohortFractionResult & r : fractions)
  {
    const CohortFraction & f = cohort.fractions[r.fraction];
    const CohortPatient &  patient = cohort.Patient(f.patient);
    o << f.fraction << "," << f.patient;
    for (const auto & c : cohort.covariateNames)
    {
      o << "," << Number(patient.covariates.at(c));
    }
    o << "," << (r.available ? "done" : "missing");
    for (const auto & m : materials)
    {
      const bool hasInterval = r.interval68.count(m) > 0;
      o << "," << (r.modulus.count(m) ? Number(r.modulus.at(m)) : "") << ","
        << (hasInterval ? Number(r.interval68.at(m)[0]) : "") << ","
        << (hasInterval ? Number(r.interval68.at(m)[1]) : "") << ","
        << (hasInterval ? (r.determined.at(m) ? "yes" : "no") : "");
    }
    o << "," << (r.available ? (r.identifiable ? "yes" : "no") : "") << ","
      << (r.available ? std::to_string(r.warnings) : "") << "," << Number(r.wallTime, 4) << "," << r.reportPath << ","
      << r.logPath << "\n";
  }
  return o.str();
}

std::string
CohortStudy::PatientsCsv() const
{
  std::ostringstream o;
  o << "# per patient and material: the recovered Young's modulus over the patient's fractions [kPa]\npatient";
  for (const auto & c : cohort.covariateNames)
  {
    o << "," << c;
  }
  o << ",material,n,missing,mean_kPa,sd_kPa,median_kPa,min_kPa,max_kPa,undetermined_intervals,"
       "mean_interval_68_width_kPa\n";
  for (const CohortPatientModulus & p : patients)
  {
    const CohortPatient & patient = cohort.Patient(p.patient);
    o << p.patient;
    for (const auto & c : cohort.covariateNames)
    {
      o << "," << Number(patient.covariates.at(c));
    }
    const bool any = p.modulus.count > 0;
    o << "," << p.material << "," << p.modulus.count << "," << p.missing << "," << (any ? Number(p.modulus.mean) : "")
      << "," << (any ? Number(p.modulus.standardDeviation) : "") << "," << (any ? Number(p.modulus.median) : "") << ","
      << (any ? Number(p.modulus.minimum) : "") << "," << (any ? Number(p.modulus.maximum) : "") << ","
      << p.undetermined << "," << Number(p.meanIntervalWidth) << "\n";
  }
  return o.str();
}

std::string
CohortStudy::CorrelationsCsv() const
{
  std::ostringstream o;
  o << "# correlation of the per-patient mean modulus with each covariate; p two-sided\n"
       "material,covariate,n,method,coefficient,statistic,p_approximate,p_permutation,permutation_exact,note\n";
  for (const CohortCorrelation & c : correlations)
  {
    if (c.tests.empty())
    {
      o << c.material << "," << c.covariate << ",,,,,,,," << c.note << "\n";
    }
    for (const CorrelationTestResult & t : c.tests)
    {
      o << c.material << "," << c.covariate << "," << t.count << "," << ToString(t.method) << ","
        << Number(t.coefficient) << "," << Number(t.statistic) << "," << Number(t.pValueApproximate) << ","
        << Number(t.pValuePermutation) << "," << (t.permutationExact ? "yes" : "no") << ",\n";
    }
  }
  return o.str();
}

std::string
CohortStudy::ReportMarkdown() const
{
  std::ostringstream o;
  const std::size_t  missing = NumberOfMissingFractions();
  o << "# Cohort study\n\n"
    << "Cohort `" << cohort.path << "`: " << cohort.patients.size() << " patients, " << fractions.size()
    << " fractions (" << fractions.size() - missing << " registered, " << missing << " missing).\n\n"
    << "## Recovered Young's modulus per patient [kPa] (dissertation Table 3.2)\n\n| patient |";
  for (const auto & c : cohort.covariateNames)
  {
    o << " " << c << " |";
  }
  o << " material | n | mean | SD | median | min | max | intervals with an undetermined end |\n|---|";
  for (std::size_t i = 0; i < cohort.covariateNames.size() + 8; ++i)
  {
    o << "---:|";
  }
  o << "\n";
  for (const CohortPatientModulus & p : patients)
  {
    const CohortPatient & patient = cohort.Patient(p.patient);
    o << "| " << p.patient << " |";
    for (const auto & c : cohort.covariateNames)
    {
      o << " " << Number(patient.covariates.at(c)) << " |";
    }
    const bool any = p.modulus.count > 0;
    o << " " << p.material << " | " << p.modulus.count
      << (p.missing ? " (" + std::to_string(p.missing) + " missing)" : "") << " | "
      << (any ? Fixed(p.modulus.mean, 2) : "–") << " | " << (any ? Fixed(p.modulus.standardDeviation, 2) : "–") << " | "
      << (any ? Fixed(p.modulus.median, 2) : "–") << " | " << (any ? Fixed(p.modulus.minimum, 2) : "–") << " | "
      << (any ? Fixed(p.modulus.maximum, 2) : "–") << " | " << p.undetermined << " |\n";
  }
  o << "\n## Correlation of the per-patient mean with the covariates (two-sided p)\n\n"
    << "| material | covariate | n | method | coefficient | p (t or normal approximation) | p (exact permutation) |\n"
    << "|---|---|---:|---|---:|---:|---:|\n";
  for (const CohortCorrelation & c : correlations)
  {
    if (c.tests.empty())
    {
      o << "| " << c.material << " | " << c.covariate << " | | | not computed: " << c.note << " | | |\n";
    }
    for (const CorrelationTestResult & t : c.tests)
    {
      o << "| " << c.material << " | " << c.covariate << " | " << t.count << " | " << ToString(t.method) << " | "
        << Fixed(t.coefficient, 3) << " | " << Fixed(t.pValueApproximate, 4) << " | "
        << (t.permutationExact ? Fixed(t.pValuePermutation, 4) : "– (more than 10 patients)") << " |\n";
    }
  }
  if (missing > 0)
  {
    o << "\n## Missing fractions (failed or not run; their logs)\n\n";
    for (const CohortFractionResult & r : fractions)
    {
      if (!r.available)
      {
        o << "- " << cohort.fractions[r.fraction].Key() << ": `" << r.logPath << "`\n";
      }
    }
  }
  return o.str();
}

} // namespace bmr

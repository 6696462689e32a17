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
#include "bmrCohort.h"

#include "bmrCsvTable.h"
#include "bmrError.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace bmr {
namespace {

const std::vector<std::string> RequiredColumns = { "patient",  "fraction",     "planning_ct", "planning_labels",
                                                   "daily_ct", "daily_labels", "scene" };
const std::vector<std::string> LandmarkColumns = { "planning_landmarks", "daily_landmarks" };

bool
IsName(const std::string & name)
{
  return !name.empty() && name != "." && name != ".." && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

/** The resolved path of \a column in \a row, which must name an existing regular file. */
std::string
ExistingFile(const CsvTable & table, const CsvRow & row, const std::string & column)
{
  const std::string & text = table.Field(row, column);
  if (text.empty())
  {
    table.FailAt(row, column, "is empty");
  }
  const std::string path = table.ResolvePath(text);
  std::error_code   error;
  if (!std::filesystem::is_regular_file(path, error))
  {
    table.FailAt(row, column, "\"" + path + "\" is not a file");
  }
  return path;
}

CohortFraction
ReadFraction(const CsvTable & table, const CsvRow & row)
{
  CohortFraction f;
  f.line = row.line;
  f.patient = table.Field(row, "patient");
  f.fraction = table.Field(row, "fraction");
  for (const char * column : { "patient", "fraction" })
  {
    if (!IsName(table.Field(row, column)))
    {
      table.FailAt(row, column, "\"" + table.Field(row, column) + "\" is not a name (letters, digits, _ - .)");
    }
  }
  f.planningCT = ExistingFile(table, row, "planning_ct");
  f.planningLabels = ExistingFile(table, row, "planning_labels");
  f.dailyCT = ExistingFile(table, row, "daily_ct");
  f.dailyLabels = ExistingFile(table, row, "daily_labels");
  f.scene = ExistingFile(table, row, "scene");
  return f;
}

void
AddCovariates(const CsvTable & table, const CsvRow & row, const std::vector<std::string> & names, CohortPatient & p)
{
  for (const auto & name : names)
  {
    double value = 0.0;
    if (!ParseCovariate(table.Field(row, name), value))
    {
      table.FailAt(row, name, "\"" + table.Field(row, name) + "\" is neither a number nor a T-stage T0 ... T4");
    }
    const auto known = p.covariates.find(name);
    if (known != p.covariates.end() && known->second != value)
    {
      table.FailAt(row, name, "differs from the value on this patient's first row");
    }
    p.covariates[name] = value;
  }
}

} // namespace

const std::vector<std::string> &
CohortFileColumns()
{
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> c = RequiredColumns;
    c.insert(c.end(), LandmarkColumns.begin(), LandmarkColumns.end());
    return c;
  }();
  return columns;
}

bool
ParseCovariate(const std::string & text, double & value)
{
  if (text.size() >= 2 && (text[0] == 'T' || text[0] == 't') && text[1] >= '0' && text[1] <= '4' &&
      (text.size() == 2 || (text.size() == 3 && std::string("abcABC").find(text[2]) != std::string::npos)))
  {
    value = double(text[1] - '0');
    return true;
  }
  if (text.empty())
  {
    return false;
  }
  char * end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

Cohort
Cohort::Read(const std::string & cohortPath)
{
  const CsvTable table = CsvTable::Read(cohortPath, "cohort");
  table.CheckColumns(RequiredColumns, {}, true);
  for (const auto & column : LandmarkColumns)
  {
    if (table.HasColumn(column))
    {
      // A fraction seen only through its markers recovers no modulus: biomechreg markers carries the anatomy
      // with known moduli. A cohort of moduli needs every fraction's daily labels.
      table.Fail("the column \"" + column +
                 "\" holds markers, which recover no modulus (biomechreg markers estimates the anatomy with known "
                 "moduli): give every fraction its daily CT and labels");
    }
  }
  Cohort cohort;
  cohort.path = cohortPath;
  for (const auto & column : table.Columns())
  {
    if (std::find(CohortFileColumns().begin(), CohortFileColumns().end(), column) == CohortFileColumns().end())
    {
      cohort.covariateNames.push_back(column);
    }
  }
  for (const CsvRow & row : table.Rows())
  {
    CohortFraction f = ReadFraction(table, row);
    for (const auto & other : cohort.fractions)
    {
      if (other.Key() == f.Key())
      {
        table.FailAt(
          row, "fraction", "\"" + f.Key() + "\" appears twice (also on line " + std::to_string(other.line) + ")");
      }
    }
    auto patient = std::find_if(
      cohort.patients.begin(), cohort.patients.end(), [&](const CohortPatient & p) { return p.name == f.patient; });
    if (patient == cohort.patients.end())
    {
      cohort.patients.push_back({ f.patient, {}, {} });
      patient = cohort.patients.end() - 1;
    }
    AddCovariates(table, row, cohort.covariateNames, *patient);
    patient->fractions.push_back(cohort.fractions.size());
    cohort.fractions.push_back(f);
  }
  if (cohort.fractions.empty())
  {
    table.Fail("holds no fraction");
  }
  return cohort;
}

const CohortPatient &
Cohort::Patient(const std::string & name) const
{
  for (const CohortPatient & p : patients)
  {
    if (p.name == name)
    {
      return p;
    }
  }
  Fail("bmr::Cohort", "cohort \"" + path + "\" has no patient \"" + name + "\"");
}

} // namespace bmr

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
#ifndef bmrCsvTable_h
#define bmrCsvTable_h

#include "BiomechanicalRegistrationExport.h"

#include <cstddef>
#include <string>
#include <vector>

namespace bmr {

/** One data row of a CSV file: its fields in header order and its line number in the file (1-based). */
struct BiomechanicalRegistration_EXPORT CsvRow
{
  std::vector<std::string> fields;
  std::size_t              line{ 0 };
};

/** \brief A comma-separated table as the project's lists are written: the first line that is not blank or a
 * '#' comment is the header, every later such line one row; fields are not quoted (paths and names hold no
 * commas), surrounding blanks and a trailing '\\r' are removed.
 *
 * Every error names the file, and where it applies the line and the column. */
class BiomechanicalRegistration_EXPORT CsvTable
{
public:
  /** Reads \a path; \a what names the table in errors ("cohort", "pair list"). Throws itk::ExceptionObject when
   * the file cannot be read, has no header, a column name is empty or repeated, or a row has another number of
   * fields than the header. */
  static CsvTable
  Read(const std::string & path, const std::string & what);

  const std::vector<std::string> &
  Columns() const
  {
    return m_Columns;
  }
  const std::vector<CsvRow> &
  Rows() const
  {
    return m_Rows;
  }
  bool
  HasColumn(const std::string & column) const;
  /** Index of \a column; throws naming the table when it is absent. */
  std::size_t
  ColumnIndex(const std::string & column) const;
  /** The field of \a row in \a column ("" for an absent optional column). */
  const std::string &
  Field(const CsvRow & row, const std::string & column) const;
  /** Throws naming the table and the first column that is not in \a required or \a optional, or the first
   * column of \a required that is missing. Pass \a allowOthers to accept further columns. */
  void
  CheckColumns(const std::vector<std::string> & required,
               const std::vector<std::string> & optional,
               bool                             allowOthers = false) const;
  /** "<what> \"<path>\" line <n>, column \"<column>\": <message>" as an itk::ExceptionObject. */
  [[noreturn]] void
  FailAt(const CsvRow & row, const std::string & column, const std::string & message) const;
  [[noreturn]] void
  Fail(const std::string & message) const;
  /** \a path resolved against the directory of the table (unchanged when it is absolute or empty). */
  std::string
  ResolvePath(const std::string & path) const;
  const std::string &
  Path() const
  {
    return m_Path;
  }

private:
  std::string              m_Path;
  std::string              m_What;
  std::vector<std::string> m_Columns;
  std::vector<CsvRow>      m_Rows;
};

} // namespace bmr

#endif

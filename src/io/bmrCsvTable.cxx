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
#include "bmrCsvTable.h"

#include "bmrError.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace bmr {
namespace {

std::string
Trimmed(const std::string & s)
{
  const std::size_t first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos)
  {
    return std::string();
  }
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string>
SplitFields(const std::string & line)
{
  std::vector<std::string> fields;
  std::size_t              start = 0;
  while (true)
  {
    const std::size_t comma = line.find(',', start);
    fields.push_back(Trimmed(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos)
    {
      return fields;
    }
    start = comma + 1;
  }
}

} // namespace

CsvTable
CsvTable::Read(const std::string & path, const std::string & what)
{
  CsvTable table;
  table.m_Path = path;
  table.m_What = what;
  std::ifstream in(path);
  if (!in)
  {
    table.Fail("cannot be opened");
  }
  std::string line;
  std::size_t number = 0;
  while (std::getline(in, line))
  {
    ++number;
    const std::string content = Trimmed(line);
    if (content.empty() || content[0] == '#')
    {
      continue;
    }
    std::vector<std::string> fields = SplitFields(content);
    if (table.m_Columns.empty())
    {
      for (std::size_t i = 0; i < fields.size(); ++i)
      {
        if (fields[i].empty() || std::find(fields.begin(), fields.begin() + i, fields[i]) != fields.begin() + i)
        {
          table.Fail("line " + std::to_string(number) + ": header column " + std::to_string(i + 1) + " is " +
                     (fields[i].empty() ? "empty" : "repeated (\"" + fields[i] + "\")"));
        }
      }
      table.m_Columns = fields;
      continue;
    }
    if (fields.size() != table.m_Columns.size())
    {
      table.Fail("line " + std::to_string(number) + ": " + std::to_string(fields.size()) + " fields, the header has " +
                 std::to_string(table.m_Columns.size()));
    }
    table.m_Rows.push_back({ fields, number });
  }
  if (in.bad())
  {
    table.Fail("could not be read to the end");
  }
  if (table.m_Columns.empty())
  {
    table.Fail("has no header line");
  }
  return table;
}

bool
CsvTable::HasColumn(const std::string & column) const
{
  return std::find(m_Columns.begin(), m_Columns.end(), column) != m_Columns.end();
}

std::size_t
CsvTable::ColumnIndex(const std::string & column) const
{
  const auto it = std::find(m_Columns.begin(), m_Columns.end(), column);
  if (it == m_Columns.end())
  {
    Fail("has no column \"" + column + "\"");
  }
  return static_cast<std::size_t>(it - m_Columns.begin());
}

const std::string &
CsvTable::Field(const CsvRow & row, const std::string & column) const
{
  static const std::string absent;
  return HasColumn(column) ? row.fields[ColumnIndex(column)] : absent;
}

void
CsvTable::CheckColumns(const std::vector<std::string> & required,
                       const std::vector<std::string> & optional,
                       bool                             allowOthers) const
{
  for (const auto & c : required)
  {
    if (!HasColumn(c))
    {
      Fail("the header lacks the column \"" + c + "\"");
    }
  }
  if (allowOthers)
  {
    return;
  }
  for (const auto & c : m_Columns)
  {
    if (std::find(required.begin(), required.end(), c) == required.end() &&
        std::find(optional.begin(), optional.end(), c) == optional.end())
    {
      Fail("unknown column \"" + c + "\"");
    }
  }
}

void
CsvTable::FailAt(const CsvRow & row, const std::string & column, const std::string & message) const
{
  Fail("line " + std::to_string(row.line) + ", column \"" + column + "\": " + message);
}

void
CsvTable::Fail(const std::string & message) const
{
  bmr::Fail("bmr::CsvTable", m_What + " \"" + m_Path + "\": " + message);
}

std::string
CsvTable::ResolvePath(const std::string & path) const
{
  if (path.empty() || path[0] == '/')
  {
    return path;
  }
  const std::size_t slash = m_Path.find_last_of('/');
  return (slash == std::string::npos ? std::string(".") : m_Path.substr(0, slash)) + "/" + path;
}

} // namespace bmr

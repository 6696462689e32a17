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
#include "bmrLandmarks.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>

namespace bmr {
namespace {

constexpr const char * Where = "bmr::ReadLandmarks";

std::string
Extension(const std::string & path)
{
  const std::size_t dot = path.find_last_of('.');
  const std::size_t slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
  {
    return std::string();
  }
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

std::string
Trim(const std::string & s)
{
  const std::size_t b = s.find_first_not_of(" \t\r");
  const std::size_t e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::vector<std::string>
SplitComma(const std::string & line)
{
  std::vector<std::string> fields;
  std::string              field;
  std::istringstream       in(line);
  while (std::getline(in, field, ','))
  {
    fields.push_back(Trim(field));
  }
  if (!line.empty() && line.back() == ',')
  {
    fields.emplace_back();
  }
  return fields;
}

double
ParseCoordinate(const std::string & text, const std::string & path, std::size_t line)
{
  std::size_t used = 0;
  double      value = std::numeric_limits<double>::quiet_NaN();
  try
  {
    value = std::stod(text, &used);
  }
  catch (const std::exception &)
  {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
  {
    Fail(Where, path + ":" + std::to_string(line) + ": \"" + text + "\" is not a finite coordinate [mm]");
  }
  return value;
}

/** RAS <-> LPS: the first two axes change sign (the conversion is its own inverse). */
std::array<double, 3>
FlipRasLps(const std::array<double, 3> & p)
{
  return { { -p[0], -p[1], p[2] } };
}

void
CheckList(const std::vector<Landmark> & landmarks, const std::string & path)
{
  if (landmarks.empty())
  {
    Fail(Where, path + ": no landmarks");
  }
  std::set<std::string> ids;
  for (const Landmark & l : landmarks)
  {
    if (!ids.insert(l.id).second)
    {
      Fail(Where, path + ": landmark id \"" + l.id + "\" appears twice");
    }
  }
}

std::vector<Landmark>
ReadCsv(std::istream & in, const std::string & path, bool slicer)
{
  std::vector<Landmark> landmarks;
  std::string           line;
  std::size_t           number = 0;
  bool                  lps = !slicer;   // our CSV is LPS; a Slicer .fcsv is RAS unless it says otherwise
  bool                  header = slicer; // a .fcsv has no column header line (its header is a comment)
  while (std::getline(in, line))
  {
    ++number;
    line = Trim(line);
    if (line.empty())
    {
      continue;
    }
    if (line[0] == '#')
    {
      std::string lower = line;
      std::transform(
        lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (slicer && lower.find("coordinatesystem") != std::string::npos)
      {
        const std::string value =
          Trim(lower.substr(lower.find('=') == std::string::npos ? lower.size() : lower.find('=') + 1));
        if (value == "lps" || value == "1")
        {
          lps = true;
        }
        else if (value == "ras" || value == "0")
        {
          lps = false;
        }
        else
        {
          Fail(Where, path + ":" + std::to_string(number) + ": unknown coordinate system \"" + value + "\"");
        }
      }
      continue;
    }
    const std::vector<std::string> f = SplitComma(line);
    if (!header)
    {
      header = true;
      if (f.size() < 4 || f[0] != "id" || f[1] != "x_mm" || f[2] != "y_mm" || f[3] != "z_mm")
      {
        Fail(Where, path + ":" + std::to_string(number) + ": expected the header \"id,x_mm,y_mm,z_mm\" (LPS mm)");
      }
      continue;
    }
    Landmark l;
    if (slicer)
    {
      // id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID
      if (f.size() < 12)
      {
        Fail(Where, path + ":" + std::to_string(number) + ": a fiducial line needs at least 12 fields");
      }
      l.id = f[11].empty() ? f[0] : f[11];
    }
    else
    {
      if (f.size() != 4)
      {
        Fail(Where, path + ":" + std::to_string(number) + ": expected 4 fields (id,x_mm,y_mm,z_mm)");
      }
      l.id = f[0];
    }
    for (int a = 0; a < 3; ++a)
    {
      l.point[a] = ParseCoordinate(f[1 + a], path, number);
    }
    if (!lps)
    {
      l.point = FlipRasLps(l.point);
    }
    landmarks.push_back(l);
  }
  return landmarks;
}

std::vector<Landmark>
ReadMarkupsJson(std::istream & in, const std::string & path)
{
  nlohmann::json root;
  try
  {
    in >> root;
  }
  catch (const std::exception & e)
  {
    Fail(Where, path + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  std::vector<Landmark> landmarks;
  if (!root.is_object() || !root.contains("markups") || !root["markups"].is_array())
  {
    Fail(Where, path + ": a markups file needs a \"markups\" array");
  }
  for (const auto & markup : root["markups"])
  {
    bool lps = false;
    if (markup.contains("coordinateSystem"))
    {
      if (!markup["coordinateSystem"].is_string())
      {
        Fail(Where, path + ": \"coordinateSystem\" must be a string");
      }
      const std::string cs = markup["coordinateSystem"].get<std::string>();
      if (cs != "LPS" && cs != "RAS")
      {
        Fail(Where, path + ": unknown coordinateSystem \"" + cs + "\" (expected LPS or RAS)");
      }
      lps = cs == "LPS";
    }
    if (!markup.contains("controlPoints") || !markup["controlPoints"].is_array())
    {
      Fail(Where, path + ": a markup needs a \"controlPoints\" array");
    }
    for (const auto & cp : markup["controlPoints"])
    {
      Landmark   l;
      const auto position = cp.find("position");
      if (position == cp.end() || !position->is_array() || position->size() != 3)
      {
        Fail(Where, path + ": control point " + std::to_string(landmarks.size()) + " needs a 3-element \"position\"");
      }
      for (int a = 0; a < 3; ++a)
      {
        if (!(*position)[a].is_number() || !std::isfinite((*position)[a].get<double>()))
        {
          Fail(Where, path + ": control point " + std::to_string(landmarks.size()) + " has a non-finite coordinate");
        }
        l.point[a] = (*position)[a].get<double>();
      }
      if (!lps)
      {
        l.point = FlipRasLps(l.point);
      }
      const auto label = cp.find("label");
      const auto id = cp.find("id");
      l.id = label != cp.end() && label->is_string() && !label->get<std::string>().empty()
               ? label->get<std::string>()
               : (id != cp.end() && id->is_string() ? id->get<std::string>() : std::to_string(landmarks.size()));
      landmarks.push_back(l);
    }
  }
  return landmarks;
}

} // namespace

std::vector<Landmark>
ReadLandmarks(const std::string & path)
{
  const std::string extension = Extension(path);
  if (extension != "csv" && extension != "fcsv" && extension != "json")
  {
    Fail(Where, path + ": unknown landmark format (expected .csv, .fcsv or .json)");
  }
  std::ifstream in(path);
  if (!in)
  {
    Fail(Where, path + ": cannot open the landmark file");
  }
  std::vector<Landmark> landmarks =
    extension == "json" ? ReadMarkupsJson(in, path) : ReadCsv(in, path, extension == "fcsv");
  CheckList(landmarks, path);
  return landmarks;
}

void
WriteLandmarks(const std::string & path, const std::vector<Landmark> & landmarks)
{
  const std::string  extension = Extension(path);
  std::ostringstream out;
  out << std::setprecision(17);
  for (const Landmark & l : landmarks)
  {
    for (double x : l.point)
    {
      if (!std::isfinite(x))
      {
        Fail("bmr::WriteLandmarks", path + ": landmark \"" + l.id + "\" has a non-finite coordinate");
      }
    }
    if (l.id.find_first_of(",\n\"") != std::string::npos)
    {
      Fail("bmr::WriteLandmarks", path + ": landmark id \"" + l.id + "\" contains a comma, quote or newline");
    }
  }
  if (extension == "csv")
  {
    out << "# landmarks, LPS physical coordinates [mm]\nid,x_mm,y_mm,z_mm\n";
    for (const Landmark & l : landmarks)
    {
      out << l.id << "," << l.point[0] << "," << l.point[1] << "," << l.point[2] << "\n";
    }
  }
  else if (extension == "fcsv")
  {
    out << "# Markups fiducial file version = 4.11\n# CoordinateSystem = LPS\n"
        << "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n";
    for (std::size_t i = 0; i < landmarks.size(); ++i)
    {
      const Landmark & l = landmarks[i];
      out << "vtkMRMLMarkupsFiducialNode_" << i << "," << l.point[0] << "," << l.point[1] << "," << l.point[2]
          << ",0,0,0,1,1,1,0," << l.id << ",,\n";
    }
  }
  else if (extension == "json")
  {
    nlohmann::json points = nlohmann::json::array();
    for (std::size_t i = 0; i < landmarks.size(); ++i)
    {
      points.push_back({ { "id", std::to_string(i + 1) },
                         { "label", landmarks[i].id },
                         { "position", { landmarks[i].point[0], landmarks[i].point[1], landmarks[i].point[2] } } });
    }
    nlohmann::json root = {
      { "@schema",
        "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
        "markups-schema-v1.0.3.json#" },
      { "markups", { { { "type", "Fiducial" }, { "coordinateSystem", "LPS" }, { "controlPoints", points } } } }
    };
    out << std::setw(2) << root << "\n";
  }
  else
  {
    Fail("bmr::WriteLandmarks", path + ": unknown landmark format (expected .csv, .fcsv or .json)");
  }
  WriteTextFileAtomically(path, out.str());
}

std::vector<std::size_t>
MatchLandmarks(const std::vector<Landmark> & a, const std::vector<Landmark> & b)
{
  if (a.empty() || a.size() != b.size())
  {
    Fail("bmr::MatchLandmarks",
         "cannot pair " + std::to_string(a.size()) + " landmarks with " + std::to_string(b.size()) +
           " (the two sets must be equal in size and not empty)");
  }
  const std::size_t     n = a.size();
  std::array<double, 3> shift{ { 0, 0, 0 } };
  for (std::size_t i = 0; i < n; ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      shift[c] += (b[i].point[c] - a[i].point[c]) / double(n);
    }
  }
  const auto cost = [&](std::size_t i, std::size_t j) {
    double d2 = 0.0;
    for (int c = 0; c < 3; ++c)
    {
      const double d = a[i].point[c] + shift[c] - b[j].point[c];
      d2 += d * d;
    }
    return d2;
  };
  std::vector<std::size_t> best(n);
  std::iota(best.begin(), best.end(), 0);
  if (n <= 8)
  {
    std::vector<std::size_t> p = best;
    double                   bestCost = std::numeric_limits<double>::infinity();
    do
    {
      double c = 0.0;
      for (std::size_t i = 0; i < n; ++i)
      {
        c += cost(i, p[i]);
      }
      // Strict comparison: the first of equal-cost permutations wins, so the result is deterministic.
      if (c < bestCost)
      {
        bestCost = c;
        best = p;
      }
    } while (std::next_permutation(p.begin(), p.end()));
    return best;
  }
  // Greedy: repeatedly take the closest remaining pair (ties by index).
  std::vector<bool> usedA(n, false), usedB(n, false);
  for (std::size_t k = 0; k < n; ++k)
  {
    double      bestCost = std::numeric_limits<double>::infinity();
    std::size_t bi = 0, bj = 0;
    for (std::size_t i = 0; i < n; ++i)
    {
      for (std::size_t j = 0; !usedA[i] && j < n; ++j)
      {
        if (!usedB[j] && cost(i, j) < bestCost)
        {
          bestCost = cost(i, j);
          bi = i;
          bj = j;
        }
      }
    }
    usedA[bi] = usedB[bj] = true;
    best[bi] = bj;
  }
  return best;
}

} // namespace bmr

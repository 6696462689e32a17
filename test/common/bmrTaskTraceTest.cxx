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
#include "bmrLinearElasticModel.h"
#include "bmrTaskTrace.h"
#include "bmrTestUtilities.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

// bmr::TaskTrace records what the library ran in parallel: checked on a linear model's factorization and solves on
// three threads, whose regions and tasks are known from the tree cut (8 bins each), and on its refusals.
namespace {

struct Row
{
  std::string kind, name;
  long        id{ 0 }, parent{ 0 }, budget{ 0 }, worker{ 0 };
  double      start{ 0.0 }, end{ 0.0 };
};

std::vector<Row>
ReadTrace(const std::string & path)
{
  std::ifstream    in(path);
  std::string      line;
  std::vector<Row> rows;
  std::getline(in, line); // header
  while (std::getline(in, line))
  {
    std::stringstream        fields(line);
    std::vector<std::string> f;
    for (std::string field; std::getline(fields, field, ',');)
    {
      f.push_back(field);
    }
    f.resize(9);
    rows.push_back({ f[0],
                     f[8],
                     std::stol(f[2]),
                     std::stol(f[3]),
                     std::stol(f[4]),
                     std::stol(f[5]),
                     std::stod(f[6]),
                     std::stod(f[7]) });
  }
  return rows;
}

/** A solve on three threads under a trace: every region's budget is min(3, its tasks) (1 with no task), every task
 * lies inside its region (times within 1 ms: the region's clock is read before and after its tasks), the
 * triangular solves' regions have one task per bin (8), and the forward and backward solves come in pairs. */
bool
CheckRecording(const std::string & path)
{
  using bmr::test::Expect;
  const bmr::TetrahedralMesh mesh = bmr::test::StructuredCube(12, 1.0, 2);
  std::vector<std::int32_t>  bottom;
  for (std::size_t n = 0; n < mesh.GetNumberOfPoints(); ++n)
  {
    if (mesh.points[3 * n + 2] == 0.0)
    {
      bottom.push_back(static_cast<std::int32_t>(n));
    }
  }
  bmr::LinearElasticModel model(mesh, { { 1, { 10.0, 0.35 } }, { 2, { 50.0, 0.45 } } });
  model.SetDirichletConditions(bottom, {});
  model.SetNumberOfSolveThreads(3);
  std::size_t regions = 0;
  {
    bmr::TaskTrace trace;
    model.Solve(std::vector<double>(3 * mesh.GetNumberOfPoints(), 1.0));
    model.Solve(std::vector<double>(3 * mesh.GetNumberOfPoints(), -1.0));
    regions = trace.GetNumberOfRegions();
    trace.Write(path);
  }
  const std::vector<Row>      rows = ReadTrace(path);
  std::map<long, const Row *> byId;
  std::map<long, long>        tasksOf;
  std::map<std::string, int>  regionsNamed;
  for (const Row & r : rows)
  {
    byId[r.id] = &r;
    regionsNamed[r.kind == "region" ? r.name : ""] += r.kind == "region" ? 1 : 0;
  }
  bool ok = Expect(!rows.empty() && rows.back().kind == "end", "the trace ends with its \"end\" row");
  ok &= Expect(regions == static_cast<std::size_t>(
                            std::count_if(rows.begin(), rows.end(), [](const Row & r) { return r.kind == "region"; })),
               "GetNumberOfRegions() counts the regions written");
  bool inside = true, budgets = true;
  for (const Row & r : rows)
  {
    if (r.kind == "task")
    {
      const auto region = byId.find(r.parent);
      inside = inside && region != byId.end() && region->second->kind == "region" &&
               r.start >= region->second->start - 1e-3 && r.end <= region->second->end + 1e-3 && r.start <= r.end;
      ++tasksOf[r.parent];
    }
  }
  bool eightBins = true;
  for (const Row & r : rows)
  {
    if (r.kind == "region")
    {
      budgets = budgets && r.budget == std::max<long>(1, std::min<long>(3, tasksOf[r.id]));
      if (r.name.rfind("solve: ", 0) == 0)
      {
        eightBins = eightBins && tasksOf[r.id] == 8;
      }
    }
  }
  std::cout << regions << " regions: " << regionsNamed["factorize: bins"] << " factorizations' bins, "
            << regionsNamed["solve: forward bins"] << " forward and " << regionsNamed["solve: backward bins"]
            << " backward solves" << std::endl;
  ok &= Expect(regionsNamed["factorize: bins"] == 1, "one factorization (its bins one region)");
  ok &= Expect(regionsNamed["solve: forward bins"] >= 2 &&
                 regionsNamed["solve: forward bins"] == regionsNamed["solve: backward bins"],
               "the forward and backward solves come in pairs, one per solve at least");
  ok &= Expect(eightBins, "each solve region has one task per bin (8)");
  ok &= Expect(inside, "every task lies inside its region");
  ok &= Expect(budgets, "every region's budget is min(3 threads, its tasks), at least 1");
  return ok;
}

bool
CheckRefusals(const std::string & directory)
{
  bool ok = true;
  {
    bmr::TaskTrace trace;
    ok &= bmr::test::ExpectException(
      "a second trace while one records", []() { bmr::TaskTrace second; }, "another task trace is recording");
    ok &= bmr::test::ExpectException(
      "a trace into a missing directory",
      [&]() { trace.Write(directory + "/missing/trace.csv"); },
      "cannot write the task trace");
  }
  bmr::TaskTrace after; // the first one stopped: a new one may record
  return ok;
}

} // namespace

int
bmrTaskTraceTest(int, char *[])
{
  const std::filesystem::path directory = std::filesystem::temp_directory_path() / "bmrTaskTraceTest";
  std::filesystem::create_directories(directory);
  bool ok = CheckRecording((directory / "trace.csv").string());
  ok &= CheckRefusals(directory.string());
  std::filesystem::remove_all(directory);
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

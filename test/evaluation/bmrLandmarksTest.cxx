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
// Landmark files round-trip in every format (to 1e-12 mm: 17 significant digits are written), 3D Slicer's
// RAS files are converted to LPS, malformed files are refused, seeds are paired after a translation and a
// permutation, and the paired t-test matches a hand computation.
#include "bmrLandmarks.h"
#include "bmrStatistics.h"
#include "bmrTestUtilities.h"
#include "itkMacro.h"
#include "itkTestingMacros.h"

#include <cmath>
#include <fstream>
#include <iostream>

namespace {
bool
Near(double a, double b, double tolerance, const char * what)
{
  if (!(std::abs(a - b) <= tolerance))
  {
    std::cerr << "FAIL: " << what << ": " << a << " != " << b << " (tolerance " << tolerance << ")" << std::endl;
    return false;
  }
  return true;
}

void
Write(const std::string & path, const std::string & text)
{
  std::ofstream(path) << text;
}
} // namespace

int
bmrLandmarksTest(int argc, char * argv[])
{
  if (argc < 2)
  {
    std::cerr << "usage: bmrLandmarksTest OUTPUT_DIRECTORY" << std::endl;
    return EXIT_FAILURE;
  }
  using bmr::test::Expect;
  using bmr::test::ToString;
  const std::string dir = argv[1];
  bool              ok = true;

  const std::vector<bmr::Landmark> seeds = { { "seed0", { { 1.25, -3.5, 12.0625 } } },
                                             { "seed1", { { -0.1, 2.0 / 3.0, 1e-3 } } },
                                             { "tip", { { 100.5, -200.25, 0.0 } } } };
  for (const std::string extension : { ".csv", ".fcsv", ".json" })
  {
    const std::string path = dir + "/landmarks" + extension;
    bmr::WriteLandmarks(path, seeds);
    const auto back = bmr::ReadLandmarks(path);
    ok &= Expect(back.size() == seeds.size(),
                 "round trip " + extension + " keeps " + ToString(seeds.size()) + " landmarks (got " +
                   ToString(back.size()) + ")");
    for (std::size_t i = 0; i < std::min(back.size(), seeds.size()); ++i)
    {
      ok &= Expect(back[i].id == seeds[i].id,
                   "round trip " + extension + " keeps id \"" + seeds[i].id + "\" (got \"" + back[i].id + "\")");
      for (int a = 0; a < 3; ++a)
      {
        ok &= Near(back[i].point[a], seeds[i].point[a], 1e-12, ("round trip " + extension).c_str());
      }
    }
  }

  // Slicer's default RAS: x and y change sign on the way to LPS.
  Write(dir + "/ras.fcsv",
        "# Markups fiducial file version = 4.11\n# CoordinateSystem = RAS\n"
        "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
        "vtkMRMLMarkupsFiducialNode_0,10,-20,30,0,0,0,1,1,1,0,F-1,,\n");
  Write(dir + "/ras.json",
        R"({"markups": [{"type": "Fiducial", "coordinateSystem": "RAS",
            "controlPoints": [{"id": "1", "label": "F-1", "position": [10, -20, 30]}]}]})");
  for (const std::string name : { "ras.fcsv", "ras.json" })
  {
    const auto l = bmr::ReadLandmarks(dir + "/" + name);
    if (Expect(l.size() == 1, name + " holds one landmark (got " + ToString(l.size()) + ")"))
    {
      ok &= Expect(l[0].id == "F-1", name + " landmark id is \"F-1\" (got \"" + l[0].id + "\")");
      ok &= Near(l[0].point[0], -10, 0, (name + " x, RAS -> LPS").c_str());
      ok &= Near(l[0].point[1], 20, 0, (name + " y, RAS -> LPS").c_str());
      ok &= Near(l[0].point[2], 30, 0, (name + " z").c_str());
    }
    else
    {
      ok = false;
    }
  }

  // Malformed files are refused.
  Write(dir + "/bad_header.csv", "x,y,z\n1,2,3\n");
  Write(dir + "/bad_number.csv", "id,x_mm,y_mm,z_mm\na,1,two,3\n");
  Write(dir + "/nan.csv", "id,x_mm,y_mm,z_mm\na,1,nan,3\n");
  Write(dir + "/duplicate.csv", "id,x_mm,y_mm,z_mm\na,1,2,3\na,4,5,6\n");
  Write(dir + "/empty.csv", "id,x_mm,y_mm,z_mm\n");
  Write(dir + "/truncated.json", "{\"markups\": [{\"controlPoints\": [");
  Write(dir + "/landmarks.txt", "id,x_mm,y_mm,z_mm\na,1,2,3\n");
  for (const std::string name : { "bad_header.csv",
                                  "bad_number.csv",
                                  "nan.csv",
                                  "duplicate.csv",
                                  "empty.csv",
                                  "truncated.json",
                                  "landmarks.txt",
                                  "missing.csv" })
  {
    ITK_TRY_EXPECT_EXCEPTION(bmr::ReadLandmarks(dir + "/" + name));
  }
  ITK_TRY_EXPECT_EXCEPTION(bmr::WriteLandmarks(dir + "/x.csv", { { "a,b", { { 0, 0, 0 } } } }));

  // Matching: b holds a's points translated by 7 mm (more than the seeds' spacing) and permuted.
  {
    const std::vector<bmr::Landmark> a = {
      { "a0", { { 0, 0, 0 } } }, { "a1", { { 6, 1, 0 } } }, { "a2", { { 1, 7, 2 } } }, { "a3", { { -4, 3, 6 } } }
    };
    const std::size_t          permutation[4] = { 2, 0, 3, 1 };
    std::vector<bmr::Landmark> b(4);
    for (std::size_t i = 0; i < 4; ++i)
    {
      b[permutation[i]] = { "b" + std::to_string(permutation[i]),
                            { { a[i].point[0] + 7.0, a[i].point[1] - 0.3, a[i].point[2] + 0.2 } } };
    }
    const auto match = bmr::MatchLandmarks(a, b);
    for (std::size_t i = 0; i < 4; ++i)
    {
      ok &= Expect(match[i] == permutation[i],
                   "landmark a" + ToString(i) + " paired with b" + ToString(permutation[i]) + " (got b" +
                     ToString(match[i]) + ")");
    }
    ITK_TRY_EXPECT_EXCEPTION(bmr::MatchLandmarks(a, std::vector<bmr::Landmark>(b.begin(), b.begin() + 3)));
  }

  // Paired t-test, by hand: d = (0.3, 0.5, -0.1, 0.6, 0.5), mean 0.36, sd = sqrt(0.312 / 4) = 0.2792848,
  // t = 0.36 / (sd / sqrt 5) = 2.8823068 with 4 degrees of freedom. For even degrees of freedom the
  // two-tailed p has a closed form: with tan(theta) = t / sqrt(4), p = 1 - sin(theta) (1 + cos^2(theta) / 2)
  // = 0.0449088 (significant at 0.05). Tolerances: 1e-9 for the arithmetic, 1e-9 for the distribution.
  {
    const auto   r = bmr::PairedTTest({ 2.1, 3.4, 1.9, 2.8, 3.0 }, { 1.8, 2.9, 2.0, 2.2, 2.5 });
    const double theta = std::atan(r.t / 2.0);
    const double closedForm = 1.0 - std::sin(theta) * (1.0 + 0.5 * std::cos(theta) * std::cos(theta));
    ok &= Near(r.meanDifference, 0.36, 1e-12, "mean difference");
    ok &= Near(r.standardDeviation, std::sqrt(0.312 / 4.0), 1e-12, "sd of the differences");
    ok &= Near(r.t, 2.8823067684915684, 1e-9, "t");
    ok &= Near(r.degreesOfFreedom, 4.0, 0.0, "degrees of freedom");
    ok &= Near(r.pValue, closedForm, 1e-9, "p against the closed form");
    ok &= Near(r.pValue, 0.044908790350366545, 1e-9, "p");
    std::cout << "paired t-test: t = " << r.t << ", p = " << r.pValue << std::endl;
    // Equal differences: sd = 0; p is 0 for a non-zero shift and 1 for none.
    const double pShift = bmr::PairedTTest({ 1, 2, 3 }, { 0, 1, 2 }).pValue;
    const double pNone = bmr::PairedTTest({ 1, 2, 3 }, { 1, 2, 3 }).pValue;
    ok &= Expect(pShift == 0.0, "equal non-zero differences give p = 0 exactly (got " + ToString(pShift) + ")");
    ok &= Expect(pNone == 1.0, "zero differences give p = 1 exactly (got " + ToString(pNone) + ")");
    ITK_TRY_EXPECT_EXCEPTION(bmr::PairedTTest({ 1.0 }, { 2.0 }));
    ITK_TRY_EXPECT_EXCEPTION(bmr::PairedTTest({ 1.0, 2.0 }, { 2.0 }));
  }
  // Summary statistics and the linear-interpolation percentile.
  {
    const auto s = bmr::Summarize({ 4, 1, 3, 2 });
    ok &= Near(s.mean, 2.5, 0, "mean");
    ok &= Near(s.median, 2.5, 0, "median");
    ok &= Near(s.maximum, 4, 0, "max");
    ok &= Near(s.standardDeviation, std::sqrt(5.0 / 3.0), 1e-15, "sd");
    ok &= Near(bmr::Percentile({ 0, 10, 20, 30, 40 }, 95.0), 38.0, 1e-12, "95th percentile");
  }
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

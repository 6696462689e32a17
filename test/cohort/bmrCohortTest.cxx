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
// The cohort file is read strictly (every refusal names the line and the column), the study's statistics are
// those of hand-made reports (means and SDs by hand, a missing fraction named with its log, Pearson r = 0.8 of
// ranks {1,2,4,3}), and the phantom cohort's draws keep their documented ranges and are reproducible; a reused
// truth mesh gives the same pair bit for bit.
#include "bmrCohortStudy.h"
#include "bmrCsvTable.h"
#include "bmrPhantom.h"
#include "bmrScene.h"
#include "bmrTestUtilities.h"
#include "itkMacro.h"
#include "itkPhantomCohort.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;

void
Write(const std::string & path, const std::string & text)
{
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

/** True when reading \a text as a cohort throws a message containing every one of \a parts. */
bool
Refuses(const std::string & dir, const std::string & text, const std::vector<std::string> & parts)
{
  const std::string path = dir + "/bad_cohort.csv";
  Write(path, text);
  try
  {
    bmr::Cohort::Read(path);
  }
  catch (const itk::ExceptionObject & e)
  {
    const std::string message = e.GetDescription();
    for (const auto & p : parts)
    {
      if (message.find(p) == std::string::npos)
      {
        std::cerr << "FAIL: the message \"" << message << "\" lacks \"" << p << "\"" << std::endl;
        return false;
      }
    }
    return true;
  }
  std::cerr << "FAIL: accepted the cohort\n" << text << std::endl;
  return false;
}

const std::string Header = "patient,fraction,t_stage,age,planning_ct,planning_labels,daily_ct,daily_labels,scene\n";

std::string
Row(const std::string & patient, const std::string & fraction, const std::string & stage, const std::string & age)
{
  return patient + "," + fraction + "," + stage + "," + age + ",img/ct.nrrd,img/labels.nrrd, img/ct.nrrd ,img/" +
         "labels.nrrd,scene.json\n";
}

bool
CheckReader(const std::string & dir)
{
  bool ok = true;
  Write(dir + "/img/ct.nrrd", "x");
  Write(dir + "/img/labels.nrrd", "x");
  Write(dir + "/scene.json", bmr::SceneToJson(bmr::PelvisPhantomScene(50.0, true)));
  const std::string good = std::string("# a comment\n") + Header + Row("P1", "F1", "T2b", "64") +
                           Row("P1", "F2", "T2b", "64") + "\n" + Row("P2", "F1", "T1c", "70.5") + "\r\n";
  Write(dir + "/cohort.csv", good);
  const bmr::Cohort c = bmr::Cohort::Read(dir + "/cohort.csv");
  ok &= Expect(c.fractions.size() == 3 && c.patients.size() == 2, "3 fractions of 2 patients");
  ok &= Expect(c.covariateNames == std::vector<std::string>{ "t_stage", "age" }, "covariates t_stage, age");
  ok &= Expect(c.patients[0].covariates.at("t_stage") == 2.0 && c.patients[1].covariates.at("t_stage") == 1.0,
               "T2b reads 2 and T1c reads 1");
  ok &= Expect(c.patients[1].covariates.at("age") == 70.5, "a numeric covariate is read");
  ok &= Expect(c.patients[0].fractions == std::vector<std::size_t>{ 0, 1 }, "P1 holds fractions 0 and 1");
  ok &= Expect(c.fractions[0].dailyCT == dir + "/img/ct.nrrd", "paths resolved against the file, blanks trimmed");
  ok &= Expect(c.fractions[2].line == 6, "the line of P2 is 6 (got " + ToString(c.fractions[2].line) + ")");

  ok &= Refuses(dir, "patient,fraction\nP1,F1\n", { "lacks the column \"planning_ct\"" });
  ok &= Refuses(dir, Header + Row("P 1", "F1", "T1", "1"), { "line 2", "column \"patient\"", "not a name" });
  ok &= Refuses(dir, Header + Row("P1", "../F1", "T1", "1"), { "line 2", "column \"fraction\"" });
  ok &= Refuses(dir, Header + Row("P1", "F1", "TX", "1"), { "line 2", "column \"t_stage\"", "\"TX\"" });
  ok &= Refuses(dir, Header + Row("P1", "F1", "T5", "1"), { "column \"t_stage\"" });
  ok &= Refuses(dir, Header + Row("P1", "F1", "T1", ""), { "column \"age\"" });
  ok &= Refuses(dir,
                Header + Row("P1", "F1", "T1", "60") + Row("P1", "F2", "T2", "60"),
                { "line 3", "column \"t_stage\"", "differs" });
  ok &= Refuses(dir,
                Header + Row("P1", "F1", "T1", "60") + Row("P1", "F1", "T1", "60"),
                { "line 3", "\"P1/F1\" appears twice (also on line 2)" });
  ok &= Refuses(dir,
                Header + "P1,F1,T1,60,img/none.nrrd,img/labels.nrrd,img/ct.nrrd,img/labels.nrrd,scene.json\n",
                { "line 2", "column \"planning_ct\"", "none.nrrd\" is not a file" });
  ok &= Refuses(dir, Header + "P1,F1,T1,60,img/ct.nrrd\n", { "line 2", "5 fields, the header has 9" });
  ok &= Refuses(dir, Header, { "holds no fraction" });
  ok &= Refuses(dir, "patient,patient\n", { "repeated (\"patient\")" });
  ok &= Refuses(dir,
                "patient,fraction,planning_ct,planning_labels,daily_ct,daily_labels,scene,daily_landmarks\n",
                { "\"daily_landmarks\" holds markers, which recover no modulus" });
  return ok;
}

std::string
Report(double E, const std::string & interval = std::string())
{
  return "{\"youngs_modulus_kPa\": {\"prostate\": " + ToString(E) + ", \"tissue\": 10}, " +
         "\"youngs_modulus_interval\": {" + interval + "}, \"identifiable\": true, \"warnings\": [\"w\"], " +
         "\"wall_time_s\": {\"total\": 2.5}}";
}

bool
CheckStudy(const std::string & dir)
{
  bool        ok = true;
  std::string text = "patient,fraction,t_stage,planning_ct,planning_labels,daily_ct,daily_labels,scene\n";
  for (const char * p : { "A", "B", "C", "D" })
  {
    for (const char * f : { "F1", "F2" })
    {
      text += std::string(p) + "," + f + ",T" + std::to_string(p[0] - 'A' + 1) +
              ",img/ct.nrrd,img/labels.nrrd,img/ct.nrrd,img/labels.nrrd,scene.json\n";
    }
  }
  Write(dir + "/study_cohort.csv", text);
  const bmr::Cohort cohort = bmr::Cohort::Read(dir + "/study_cohort.csv");
  const std::string study = dir + "/study";
  // Patient means 10, 20, 40, 30 kPa: ranks {1, 2, 4, 3} against the stages 1 ... 4, so r = rho = 0.8 by hand
  // (centred products 2.25 + 0.25 + 0.75 + 0.75 = 4 over 5) and tau-b = (5 - 1) / 6.
  Write(study + "/results/A/F1/report.json", Report(9));
  Write(study + "/results/A/F2/report.json", Report(11));
  Write(study + "/results/B/F1/report.json", Report(19));
  Write(study + "/results/B/F2/report.json", Report(21));
  Write(study + "/results/C/F1/report.json",
        Report(0,
               "\"prostate\": {\"estimate_kPa\": 40, \"interval_68_kPa\": [30, 52], \"lower_end_determined\": "
               "true, \"upper_end_determined\": false}"));
  Write(study + "/results/D/F1/report.json", Report(29));
  Write(study + "/results/D/F2/report.json", Report(31));
  const bmr::CohortStudy s = bmr::CohortStudy::Summarize(cohort, study);
  ok &= Expect(s.materials == std::vector<std::string>{ "prostate" }, "the scene's unknown material only");
  ok &= Expect(s.NumberOfMissingFractions() == 1, "C/F2 is missing");
  const auto & a = s.patients[0].modulus;
  ok &= Expect(std::abs(a.mean - 10.0) < 1e-12 && std::abs(a.standardDeviation - std::sqrt(2.0)) < 1e-12,
               "A: mean 10, SD sqrt 2 (exact to 1e-12; got " + ToString(a.mean) + ", " + ToString(a.standardDeviation) +
                 ")");
  const auto & c = s.patients[2];
  ok &= Expect(c.modulus.count == 1 && c.modulus.mean == 40.0 && c.missing == 1 && c.undetermined == 1 &&
                 c.meanIntervalWidth == 22.0,
               "C: the interval's estimate 40 from one fraction, one missing, one undetermined end, width 22");
  ok &= Expect(s.correlations.size() == 1 && s.correlations[0].tests.size() == 3, "three tests on t_stage");
  if (s.correlations.size() == 1 && s.correlations[0].tests.size() == 3)
  {
    const auto & t = s.correlations[0].tests;
    ok &= Expect(std::abs(t[0].coefficient - 0.8) < 1e-12 && std::abs(t[1].coefficient - 0.8) < 1e-12,
                 "Pearson and Spearman 0.8 (to 1e-12; got " + ToString(t[0].coefficient) + ", " +
                   ToString(t[1].coefficient) + ")");
    ok &= Expect(std::abs(t[2].coefficient - 4.0 / 6.0) < 1e-12, "Kendall tau-b 2/3 (to 1e-12)");
  }
  ok &= Expect(s.ReportMarkdown().find("C/F2: `" + study + "/logs/C/F2.log`") != std::string::npos,
               "the report names the missing fraction's log");
  ok &= Expect(s.FractionsCsv().find("F2,C,3,missing") != std::string::npos, "fractions.csv marks C/F2 missing");
  ok &= Expect(s.PatientsCsv().find("A,1,prostate,2,0,10,1.41421,10,9,11,0,0") != std::string::npos,
               "patients.csv row of A");
  Write(study + "/results/C/F2/report.json", "{\"youngs_modulus_kPa\": ");
  try
  {
    bmr::CohortStudy::Summarize(cohort, study);
    ok &= Expect(false, "a truncated report is refused");
  }
  catch (const itk::ExceptionObject & e)
  {
    ok &= Expect(std::string(e.GetDescription()).find("C/F2") != std::string::npos, "the error names C/F2");
  }
  return ok;
}

bool
CheckPhantomCohort()
{
  bool                       ok = true;
  const bmr::PelvisClearance base = bmr::MeasurePelvisClearance(bmr::PelvisAnatomy());
  std::cout << "default anatomy: organs " << base.organToOrgan << " mm apart (" << base.closestOrgans << "), "
            << base.organToBoneOrOutline << " mm from bone or outline (" << base.closestToBoneOrOutline << ")"
            << std::endl;
  ok &= Expect(base.organToOrgan >= 3.0 && base.organToBoneOrOutline >= 5.0,
               "the default anatomy keeps the clearances the cohort asks for (3 and 5 mm)");
  bmr::PelvisAnatomy touching;
  touching.bladderScale = 1.35; // semi-axis 45.9 mm across: into the ilia, whose inner faces are 44 mm out
  ok &= Expect(bmr::MeasurePelvisClearance(touching).organToBoneOrOutline < 5.0,
               "a 1.35 x bladder comes within 5 mm of a bone");

  itk::PhantomCohortSettings s;
  s.patients = 6;
  s.fractions = 3;
  s.seed = 11;
  const auto cohort = itk::DrawPhantomCohort(s);
  s.patients = 7;
  const auto more = itk::DrawPhantomCohort(s);
  for (std::size_t p = 0; p < cohort.size(); ++p)
  {
    const auto & c = cohort[p];
    ok &= Expect(c.prostateE == more[p].prostateE && c.anatomy.prostateScale == more[p].anatomy.prostateScale &&
                   c.fractions[2].bladderMM == more[p].fractions[2].bladderMM,
                 c.name + ": a seventh patient leaves the first six as they were");
    ok &= Expect(c.stage >= 1 && c.stage <= 3, c.name + ": stage within T1-T3");
    const double median = s.stageMedianE[c.stage - 1];
    ok &= Expect(std::abs(std::log(c.prostateE / median)) <= 4 * s.logSpread + 0.5 / median,
                 c.name + ": E " + ToString(c.prostateE) + " within 4 spreads of its stage's median");
    ok &= Expect(c.clearance.organToOrgan >= 3.0 && c.clearance.organToBoneOrOutline >= 5.0,
                 c.name + ": the drawn anatomy keeps its clearances");
    ok &= Expect(c.anatomy.prostateScale >= 0.85 && c.anatomy.prostateScale < 1.2 && c.anatomy.rectumRadius >= 11 &&
                   c.anatomy.rectumRadius < 14,
                 c.name + ": the anatomy within its documented ranges");
    for (const auto & f : c.fractions)
    {
      ok &= Expect(f.planningSeed == c.fractions[0].planningSeed && f.seed != c.fractions[0].planningSeed &&
                     f.bladderMM >= 2.0 && f.bladderMM <= 8.0 && f.rectumMM >= 1.0 && f.rectumMM <= 5.0,
                   c.name + ": fractions share the planning scan and have fillings within range");
    }
  }
  return ok;
}

/** A patient's second fraction made with the truth mesh of its first is the pair made from scratch, bit for bit
 * (CGAL meshes one planning anatomy the same way every time; the cohort writer relies on it). Small grid (2 x 2 x 4
 * mm) and a coarse truth mesh to keep it to seconds. */
bool
CheckTruthMeshReuse()
{
  itk::PhantomCohortSettings s;
  s.patients = 1;
  s.fractions = 2;
  s.seed = 5;
  s.base.grid.size = { { 100, 80, 40 } };
  s.base.grid.spacing = { { 2.0, 2.0, 4.0 } };
  s.base.truthRefinement = 2.0;
  const auto           patient = itk::DrawPhantomCohort(s).front();
  bmr::TetrahedralMesh truthMesh;
  itk::MakePhantomPair(patient.fractions[0], nullptr, truthMesh);
  const std::size_t      tetrahedra = truthMesh.GetNumberOfTetrahedra();
  const itk::PhantomPair reused = itk::MakePhantomPair(patient.fractions[1], nullptr, truthMesh);
  const itk::PhantomPair fresh = itk::MakePhantomPair(patient.fractions[1]);
  const auto *           a = reused.truthField->GetBufferPointer();
  const auto *           b = fresh.truthField->GetBufferPointer();
  std::size_t            differing = 0;
  for (std::size_t i = 0; i < reused.truthField->GetBufferedRegion().GetNumberOfPixels(); ++i)
  {
    differing += a[i] != b[i];
  }
  std::cout << "truth mesh reuse: " << tetrahedra << " tetrahedra, " << differing << " differing field voxels"
            << std::endl;
  return Expect(tetrahedra > 0 && truthMesh.GetNumberOfTetrahedra() == tetrahedra && differing == 0 &&
                  reused.truthTetrahedra == fresh.truthTetrahedra,
                "a reused truth mesh gives the pair made from scratch, bit for bit (" + ToString(differing) +
                  " voxels differ)");
}
} // namespace

int
bmrCohortTest(int argc, char * argv[])
{
  if (argc < 2)
  {
    std::cerr << "usage: bmrCohortTest OUTPUT_DIRECTORY" << std::endl;
    return EXIT_FAILURE;
  }
  const std::string dir = argv[1];
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  bool ok = CheckReader(dir);
  ok &= CheckStudy(dir);
  ok &= CheckPhantomCohort();
  ok &= CheckTruthMeshReuse();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

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
#include "itkPhantomCohort.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"
#include "bmrLandmarks.h"
#include "bmrRandom.h"
#include "itkBiomechanicalImageIO.h"
#include "itkBiomechanicalReports.h"
#include "itkBiomechanicalWriters.h"

#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

namespace itk {
namespace {

constexpr const char * Where = "itk::DrawPhantomCohort";
constexpr double       MinimumOrganGap = 3.0;      // mm
constexpr double       MinimumBoneOrOutline = 5.0; // mm
constexpr unsigned int MaximumAnatomyDraws = 50;

double
StandardNormal(std::mt19937_64 & rng)
{
  // Box-Muller on the raw integers: the same numbers on every standard library.
  const double u1 = 1.0 - bmr::Uniform(rng, 0.0, 1.0);
  const double u2 = bmr::Uniform(rng, 0.0, 1.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

bmr::PelvisAnatomy
DrawAnatomy(std::mt19937_64 & rng, bmr::PelvisClearance & clearance)
{
  for (unsigned int attempt = 0; attempt < MaximumAnatomyDraws; ++attempt)
  {
    bmr::PelvisAnatomy a;
    a.prostateScale = bmr::Uniform(rng, 0.85, 1.2);
    a.bladderScale = bmr::Uniform(rng, 0.85, 1.1);
    a.rectumRadius = bmr::Uniform(rng, 11.0, 14.0);
    for (double & d : a.offset)
    {
      d = bmr::Uniform(rng, -3.0, 3.0);
    }
    clearance = bmr::MeasurePelvisClearance(a);
    if (clearance.organToOrgan >= MinimumOrganGap && clearance.organToBoneOrOutline >= MinimumBoneOrOutline)
    {
      return a;
    }
  }
  bmr::Fail(Where, "no anatomy kept its organs apart in " + std::to_string(MaximumAnatomyDraws) + " draws");
}

void
CheckSettings(const PhantomCohortSettings & s)
{
  const auto range = [](const std::array<double, 2> & r) { return r[0] >= 0.0 && r[1] >= r[0] && r[1] <= 30.0; };
  if (s.patients < 1 || s.patients > 999 || s.fractions < 1 || s.fractions > 99)
  {
    bmr::Fail(Where, "patients must lie in [1, 999] and fractions in [1, 99]");
  }
  if (!(s.stages[0] >= 1 && s.stages[1] >= s.stages[0] && s.stages[1] <= 4))
  {
    bmr::Fail(Where, "the stages must lie within T1 ... T4");
  }
  if (!range(s.bladderMM) || !range(s.rectumMM) || !(s.logSpread >= 0.0 && s.logSpread <= 1.0))
  {
    bmr::Fail(Where, "fillings must be ranges within [0, 30] mm and the log spread lie in [0, 1]");
  }
  if (s.base.anatomy != PhantomSettings::AnatomyEnum::Pelvis)
  {
    bmr::Fail(Where, "a cohort is drawn on the pelvis phantom");
  }
}

} // namespace

std::vector<PhantomCohortPatient>
DrawPhantomCohort(const PhantomCohortSettings & s)
{
  CheckSettings(s);
  std::vector<PhantomCohortPatient> cohort;
  for (unsigned int p = 1; p <= s.patients; ++p)
  {
    const std::uint64_t  patientSeed = s.seed * 1000 + p;
    std::mt19937_64      rng(patientSeed);
    PhantomCohortPatient patient;
    std::ostringstream   name;
    name << "P" << std::setw(2) << std::setfill('0') << p;
    patient.name = name.str();
    patient.stage = s.stages[0] + int(std::floor(bmr::Uniform(rng, 0.0, 1.0) * (s.stages[1] - s.stages[0] + 1)));
    patient.stage = std::min(patient.stage, s.stages[1]);
    patient.prostateE = std::round(s.stageMedianE[patient.stage - 1] * std::exp(s.logSpread * StandardNormal(rng)));
    patient.anatomy = DrawAnatomy(rng, patient.clearance);
    for (unsigned int f = 1; f <= s.fractions; ++f)
    {
      PhantomSettings fraction = s.base;
      fraction.prostateE = patient.prostateE;
      fraction.organs = patient.anatomy;
      fraction.planningSeed = patientSeed;
      fraction.seed = patientSeed * 100 + f;
      fraction.bladderMM = std::round(100.0 * bmr::Uniform(rng, s.bladderMM[0], s.bladderMM[1])) / 100.0;
      fraction.rectumMM = std::round(100.0 * bmr::Uniform(rng, s.rectumMM[0], s.rectumMM[1])) / 100.0;
      patient.fractions.push_back(fraction);
    }
    cohort.push_back(patient);
  }
  return cohort;
}

namespace {
/** Writes one pair of a phantom patient: with the first fraction the planning scan and scene, then the daily scan,
 * its seeds and its truth. Returns the cohort file's line of the fraction. */
std::string
WriteCohortFraction(const std::string &          directory,
                    const PhantomCohortPatient & patient,
                    std::size_t                  f,
                    const PhantomPair &          pair)
{
  const std::string patientDir = directory + "/" + patient.name;
  const std::string fraction = "F" + std::to_string(f + 1);
  const std::string dailyDir = patientDir + "/" + fraction;
  MakeOutputDirectory(dailyDir);
  if (f == 0)
  {
    WriteImageAtomically(pair.movingCT.GetPointer(), patientDir + "/planning_ct.nrrd");
    WriteImageAtomically(pair.movingLabels.GetPointer(), patientDir + "/planning_labels.nrrd");
    bmr::Scene scene = pair.scene;
    scene.movingLandmarks.clear();
    scene.fixedLandmarks.clear();
    bmr::WriteTextFileAtomically(patientDir + "/scene.json", bmr::SceneToJson(scene));
    bmr::WriteLandmarks(patientDir + "/seeds_planning.csv", pair.movingLandmarks);
  }
  WriteImageAtomically(pair.fixedCT.GetPointer(), dailyDir + "/daily_ct.nrrd");
  WriteImageAtomically(pair.fixedLabels.GetPointer(), dailyDir + "/daily_labels.nrrd");
  bmr::WriteLandmarks(dailyDir + "/seeds_daily.csv", pair.fixedLandmarks);
  bmr::WriteTextFileAtomically(dailyDir + "/truth.json", PhantomTruthJson(pair, patient.fractions[f]));
  const std::string p = patient.name + "/";
  return patient.name + "," + fraction + ",T" + std::to_string(patient.stage) + "," + p + "planning_ct.nrrd," + p +
         "planning_labels.nrrd," + p + fraction + "/daily_ct.nrrd," + p + fraction + "/daily_labels.nrrd," + p +
         "scene.json\n";
}

std::string
TruthPatientLine(const PhantomCohortPatient & p)
{
  std::ostringstream o;
  const auto &       a = p.anatomy;
  o << p.name << ",T" << p.stage << "," << p.prostateE << "," << a.prostateScale << "," << a.bladderScale << ","
    << a.rectumRadius << "," << a.offset[0] << "," << a.offset[1] << "," << a.offset[2] << ","
    << p.clearance.organToOrgan << "," << p.clearance.organToBoneOrOutline << "\n";
  return o.str();
}

std::string
TruthCorrelationsCsv(const std::vector<bmr::CorrelationTestResult> & tests)
{
  std::ostringstream o;
  o << "# the truth: prostate modulus against T-stage over the patients; p two-sided\n"
       "method,n,coefficient,p_approximate,p_permutation\n";
  for (const auto & t : tests)
  {
    o << bmr::ToString(t.method) << "," << t.count << "," << t.coefficient << "," << t.pValueApproximate << ","
      << t.pValuePermutation << "\n";
  }
  return o.str();
}
} // namespace

std::vector<bmr::CorrelationTestResult>
PhantomCohortTruthCorrelations(const std::vector<PhantomCohortPatient> & cohort)
{
  std::vector<bmr::CorrelationTestResult> tests;
  std::vector<double>                     stage, modulus;
  for (const auto & p : cohort)
  {
    stage.push_back(p.stage);
    modulus.push_back(p.prostateE);
  }
  for (auto method :
       { bmr::CorrelationEnum::Pearson, bmr::CorrelationEnum::Spearman, bmr::CorrelationEnum::KendallTauB })
  {
    if (cohort.size() >= 3)
    {
      tests.push_back(bmr::CorrelationTest(stage, modulus, method));
    }
  }
  return tests;
}

void
WritePhantomCohort(const std::string &                       directory,
                   const std::vector<PhantomCohortPatient> & cohort,
                   PipelineObserver *                        observer)
{
  MakeOutputDirectory(directory);
  std::string cohortCsv = "# a phantom cohort (biomechreg phantom-cohort); its truth: truth.csv, truth_fractions.csv\n"
                          "patient,fraction,t_stage,planning_ct,planning_labels,daily_ct,daily_labels,scene\n";
  std::string truthCsv =
    "# per patient: T-stage, true prostate modulus [kPa], anatomy (scales, mm) and clearances [mm]\n"
    "patient,t_stage,true_E_kPa,prostate_scale,bladder_scale,rectum_radius_mm,offset_x_mm,"
    "offset_y_mm,offset_z_mm,organ_gap_mm,bone_or_outline_gap_mm\n";
  std::ostringstream fractions;
  fractions << "# per fraction: the fillings [mm] and the random seed of its pair\n"
               "patient,fraction,bladder_mm,rectum_mm,seed\n";
  for (const auto & patient : cohort)
  {
    truthCsv += TruthPatientLine(patient);
    bmr::TetrahedralMesh truthMesh; // one planning anatomy per patient: meshed with the first fraction
    for (std::size_t f = 0; f < patient.fractions.size(); ++f)
    {
      const PhantomSettings & o = patient.fractions[f];
      cohortCsv += WriteCohortFraction(directory, patient, f, MakePhantomPair(o, observer, truthMesh));
      fractions << patient.name << ",F" << f + 1 << "," << o.bladderMM << "," << o.rectumMM << "," << o.seed << "\n";
    }
  }
  bmr::WriteTextFileAtomically(directory + "/truth.csv", truthCsv);
  bmr::WriteTextFileAtomically(directory + "/truth_fractions.csv", fractions.str());
  bmr::WriteTextFileAtomically(directory + "/truth_correlations.csv",
                               TruthCorrelationsCsv(PhantomCohortTruthCorrelations(cohort)));
  bmr::WriteTextFileAtomically(directory + "/cohort.csv", cohortCsv);
}

} // namespace itk

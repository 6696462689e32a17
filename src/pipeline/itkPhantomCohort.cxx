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

#include "bmrError.h"
#include "itkPipelineStages.h"

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
  const double u1 = 1.0 - pipeline::Uniform(rng, 0.0, 1.0);
  const double u2 = pipeline::Uniform(rng, 0.0, 1.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
}

bmr::PelvisAnatomy
DrawAnatomy(std::mt19937_64 & rng, bmr::PelvisClearance & clearance)
{
  for (unsigned int attempt = 0; attempt < MaximumAnatomyDraws; ++attempt)
  {
    bmr::PelvisAnatomy a;
    a.prostateScale = pipeline::Uniform(rng, 0.85, 1.2);
    a.bladderScale = pipeline::Uniform(rng, 0.85, 1.1);
    a.rectumRadius = pipeline::Uniform(rng, 11.0, 14.0);
    for (double & d : a.offset)
    {
      d = pipeline::Uniform(rng, -3.0, 3.0);
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
    patient.stage = s.stages[0] + int(std::floor(pipeline::Uniform(rng, 0.0, 1.0) * (s.stages[1] - s.stages[0] + 1)));
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
      fraction.bladderMM = std::round(100.0 * pipeline::Uniform(rng, s.bladderMM[0], s.bladderMM[1])) / 100.0;
      fraction.rectumMM = std::round(100.0 * pipeline::Uniform(rng, s.rectumMM[0], s.rectumMM[1])) / 100.0;
      patient.fractions.push_back(fraction);
    }
    cohort.push_back(patient);
  }
  return cohort;
}

} // namespace itk

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
// The library's registration pipeline end to end, without the command line: itk::MakePhantomPair makes a pelvis
// pair at 1 mm (prostate 60 kPa, bladder +8 mm, rectum +4 mm, a seed of its own; the fixed scan from a finer,
// independently seeded mesh), itk::RegisterSegmentedPair registers it as a user's scans would be registered,
// and the stated modulus (the default rescan interval's centre) must lie within 20 % of the truth with a
// determined, nested 95 % interval of a plausible width from the default 4 rescans, bring the prostate
// surface within half a voxel, warp the labels onto the fixed ones (prostate Dice > 0.9), produce the field on the
// fixed grid and a report that names the gauge; the in-memory result must equal what the report says.
//
// Coverage is not checked here: one realization cannot check it, since a calibrated 95 % interval misses one pair in
// twenty by design. This pair is such a miss (fit +8.8 %, the truth 1.45 half-widths below the 95 % interval's lower
// end); the calibration benchmark checks coverage on 30 fresh pairs (0.73 / 0.97 at 68 / 95 %,
// docs/history/benchmarks.md). Why 20 %: one mesh's estimate scatters about the mean of other meshes of nearly the same
// sizes with an SD of 4-8 % (docs/history/benchmarks.md, mesh convergence), and single pairs at 30-150 kPa in the
// calibration and Table 3.1 runs erred by up to 15.6 % (90th percentile 10-11.5 %). The sliver bound moves this one
// pair's estimate by a few percent while the mean over many meshes stays put, so the tolerance leaves room for it.
// 20 % still fails an estimator that is off by the 25-76 % of the stiff-organ misses issue 15 reported.
#include "itkBiomechanicalPipelines.h"
#include "bmrTestUtilities.h"
#include "itkBiomechanicalWriters.h"
#include "itkBiomechanicalReports.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <iostream>

int
itkRegistrationPipelineTest(int, char *[])
{
  itk::PhantomSettings phantom;
  phantom.grid.size = { { 200, 160, 160 } };
  phantom.grid.spacing = { { 1.0, 1.0, 1.0 } };
  phantom.grid.origin = { { -99.5, -79.5, -79.5 } };
  phantom.prostateE = 60.0;
  phantom.bladderMM = 8.0;
  phantom.rectumMM = 4.0;
  phantom.seed = 3;
  const itk::PhantomPair pair = itk::MakePhantomPair(phantom);

  itk::RegistrationSettings settings;
  settings.elementState = false; // as biomechreg register without mesh.vtu among its outputs
  const itk::RegistrationResult r =
    itk::RegisterSegmentedPair(pair.movingLabels, pair.fixedLabels, pair.movingCT, pair.scene, settings);
  const itk::ModulusInterval & stated = r.modulusInterval.at("prostate");
  const double                 E = stated.estimate;
  double                       rms = -1.0;
  for (const auto & s : r.estimation.residuals)
  {
    rms = s.name == "prostate" ? s.rms : rms;
  }
  const auto report = nlohmann::json::parse(itk::RegistrationReportJson(r, settings, r.state.stages));
  std::cout << "prostate: true " << phantom.prostateE << " kPa, fit " << r.youngsModulus.at("prostate") << " kPa"
            << itk::UncertaintyText(r, "prostate") << "; surface RMS " << rms << " mm; Dice " << r.dice.at("prostate")
            << "; " << r.state.warnings.size() << " warnings" << std::endl;

  bool ok = true;
  ok &= bmr::test::Expect(std::abs(E / phantom.prostateE - 1.0) <= 0.20,
                          "stated prostate modulus within 20 % of the truth");
  ok &= bmr::test::Expect(stated.lowerDetermined && stated.upperDetermined && stated.resampleModuli.size() == 4,
                          "the 95 % interval is determined, from 4 rescans");
  ok &= bmr::test::Expect(stated.interval95[0] <= stated.interval68[0] && stated.interval68[0] <= E &&
                            E <= stated.interval68[1] && stated.interval68[1] <= stated.interval95[1],
                          "the 68 % interval lies inside the 95 % one and holds the stated modulus");
  // 1 % to 100 %: the 95 % half-widths (log E) of the 50 determined intervals at 30-150 kPa in the calibration and
  // Table 3.1 runs lie within 4.5-67 % (median 22 %); identical rescans (no spread) or an exploded spread fail.
  const double halfWidth95 = 0.5 * std::log(stated.interval95[1] / stated.interval95[0]);
  ok &= bmr::test::Expect(halfWidth95 > 0.01 && halfWidth95 < 1.0, "the 95 % half-width (log E) between 1 % and 100 %");
  ok &= bmr::test::Expect(rms >= 0.0 && rms < 0.5, "prostate surface RMS below half a voxel (0.5 mm)");
  ok &= bmr::test::Expect(r.dice.at("prostate") > 0.9, "prostate Dice of the warped labels above 0.9");
  ok &= bmr::test::Expect(r.estimation.identifiable, "the modulus is identifiable");
  ok &= bmr::test::Expect(r.gaugeLabel == "soft_tissue" && r.gaugeModulus == 10.0, "gauge soft_tissue at 10 kPa");
  ok &= bmr::test::Expect(r.state.pullBack && r.state.pullBack->GetLargestPossibleRegion() ==
                                                pair.fixedLabels->GetLargestPossibleRegion(),
                          "the field lies on the fixed labels' grid");
  ok &= bmr::test::Expect(r.warpedCT && r.warpedLabels, "warped CT and labels");
  ok &= bmr::test::Expect(report["youngs_modulus_kPa"]["prostate"].get<double>() == r.youngsModulus.at("prostate"),
                          "report.json holds the fit's modulus");
  ok &= bmr::test::Expect(report["youngs_modulus_interval"]["prostate"]["estimate_kPa"].get<double>() == E,
                          "report.json holds the stated modulus");
  ok &= bmr::test::Expect(report["gauge"]["label"] == "soft_tissue", "report.json names the gauge");
  // Without the element state: the nodal solution only, and mesh.vtu refused (naming the setting), not written.
  ok &= bmr::test::Expect(r.state.simulation.vonMises.empty() && r.state.simulation.youngsModulus.empty() &&
                            r.state.simulation.displacement == r.state.mesh.displacement,
                          "elementState off: no per-element stress or moduli, the nodal displacement kept");
  const std::string vtu = (std::filesystem::temp_directory_path() / "bmr_pipeline_test_state.vtu").string();
  std::filesystem::remove(vtu);
  std::string refusal;
  try
  {
    itk::WriteSimulationMesh(vtu, r.state);
  }
  catch (const itk::ExceptionObject & e)
  {
    refusal = e.GetDescription();
  }
  ok &= bmr::test::Expect(refusal.find("elementState") != std::string::npos && !std::filesystem::exists(vtu),
                          "mesh.vtu of a state without element fields refused naming elementState: " + refusal);
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

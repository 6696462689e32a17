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
#include "itkBiomechanicalReports.h"

#include "itkMarkerPipeline.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace itk {
namespace {
using Json = nlohmann::ordered_json;

/** A number for JSON, which has no infinity: null when not finite. */
Json
Number(double x)
{
  return std::isfinite(x) ? Json(x) : Json(nullptr);
}

/** A whole number as a JSON integer ("100", not "100.0"), as scene files and scripts write moduli. */
Json
Compact(double x)
{
  return std::isfinite(x) && x == std::round(x) && std::abs(x) < 1e15 ? Json(static_cast<std::int64_t>(x)) : Json(x);
}

/** Every stage's wall time [s] and their total. */
Json
WallTimes(const std::vector<PipelineStage> & stages)
{
  Json   times = Json::object();
  double total = 0.0;
  for (const PipelineStage & s : stages)
  {
    times[s.name] = s.seconds;
    total += s.seconds;
  }
  times["total"] = total;
  return times;
}

Json
Units()
{
  return { { "length", "mm" }, { "modulus", "kPa" }, { "force", "mN" }, { "phi", "mm^2" }, { "time", "s" } };
}

Json
ModulusSection(const RegistrationResult & r, const bmr::WallLoadSettings & walls)
{
  Json uncertainty = Json::object();
  for (const auto & kv : r.modulusUncertainty)
  {
    const double E = r.youngsModulus.at(kv.first);
    uncertainty[kv.first] = { { "sigma_log_E", Number(kv.second) },
                              { "one_sigma_interval_kPa",
                                { Number(E * std::exp(-kv.second)), Number(E * std::exp(kv.second)) } } };
  }
  Json j;
  j["youngs_modulus_kPa"] = r.youngsModulus;
  j["gauge"] = { { "label", r.gaugeLabel }, { "youngs_modulus_kPa", r.gaugeModulus } };
  j["identifiable"] = r.estimation.identifiable;
  j["slice_interpolation"] = r.slicesInterpolated;
  j["identifiability"] = r.estimation.identifiabilityMessage;
  j["youngs_modulus_uncertainty"] = uncertainty;
  Json intervals = Json::object();
  for (const auto & kv : r.modulusInterval)
  {
    const ModulusInterval & i = kv.second;
    std::vector<Json>       resamples;
    for (double E : i.resampleModuli)
    {
      resamples.push_back(Number(E));
    }
    intervals[kv.first] = { { "method", i.method },
                            { "quantiles", i.quantiles },
                            { "estimate_kPa", Number(i.estimate) },
                            { "fit_kPa", Number(i.fit) },
                            { "log_bias", Number(i.logBias) },
                            { "bias_corrected", i.biasCorrected },
                            { "sigma_log_E", Number(i.logSigma) },
                            { "censored_resamples", i.censoredResamples },
                            { "interval_68_kPa", { Number(i.interval68[0]), Number(i.interval68[1]) } },
                            { "interval_95_kPa", { Number(i.interval95[0]), Number(i.interval95[1]) } },
                            { "lower_end_determined", i.lowerDetermined },
                            { "upper_end_determined", i.upperDetermined },
                            { "statement", ModulusIntervalText(kv.first, i) },
                            { "not_determined_reason", i.notDeterminedReason },
                            { "assumes", WallLawCaveat(walls) },
                            { "resamples_kPa", resamples } };
    if (i.method == "slice-calibration")
    {
      intervals[kv.first]["calibrated_slice_mm"] = i.calibratedSliceMM;
    }
  }
  j["youngs_modulus_interval"] = intervals;
  return j;
}
} // namespace

std::string
RegistrationReportJson(const RegistrationResult &         r,
                       const RegistrationSettings &       settings,
                       const std::vector<PipelineStage> & wallTimes)
{
  Json j;
  j["units"] = Units();
  j.update(ModulusSection(r, settings.walls));
  j["residual_standard_deviation_mm"] = r.estimation.residualStandardDeviation;
  j["final_phi_mm2"] = r.estimation.value;
  Json surfaces = Json::object();
  for (const auto & s : r.estimation.residuals)
  {
    surfaces[s.name] = { { "rms", s.rms }, { "max", s.maximum }, { "mean_signed", s.mean } };
  }
  j["surface_distance_mm"] = surfaces;
  j["dice"] = r.dice;
  Json volumes = Json::object();
  for (const auto & [name, v] : r.labelVolumeML)
  {
    volumes[name] = { { "moving", v[0] }, { "fixed", v[1] } };
  }
  j["label_volume_ml"] = volumes;
  j["jacobian_determinant"] = { { "minimum", r.jacobianMinimum },
                                { "fraction_nonpositive", r.jacobianNonPositiveFraction } };
  j["inverted_elements"] = r.state.invertedElements;
  j["step_limit"] = { { "element_inversion", settings.estimator.limitElementInversion ? "limit" : "allow" },
                      { "rejected_trial_points", r.estimation.rejectedSteps } };
  j["warnings"] = r.state.warnings;
  j["mesh"] = { { "tetrahedra", r.state.mesh.GetNumberOfTetrahedra() }, { "nodes", r.state.mesh.GetNumberOfPoints() } };
  j["iterations"] = { { "sweep", r.estimation.sweep.size() }, { "fine", r.estimation.history.size() } };
  j["wall_time_s"] = WallTimes(wallTimes);
  return j.dump(2) + "\n";
}

std::string
MarkerReportJson(const MarkerResult & r, const MarkerSettings & settings)
{
  Json j;
  j["units"] = Units();
  j["markers"] = r.markerIds;
  Json methods = Json::object();
  for (const MarkerMethodResult & m : r.methods)
  {
    Json entry = { { "fit_residual_mm", m.fitResidual } };
    if (m.leaveOneOutRms >= 0.0)
    {
      entry["leave_one_out_error_mm"] = m.leaveOneOutError;
      entry["leave_one_out_rms_mm"] = m.leaveOneOutRms;
    }
    if (m.leaveOneOutTrueRms >= 0.0)
    {
      // Against the true positions (phantoms): without the left-out marker's tracking noise.
      entry["leave_one_out_true_error_mm"] = m.leaveOneOutTrueError;
      entry["leave_one_out_true_rms_mm"] = m.leaveOneOutTrueRms;
    }
    if (m.intersectionOverUnion >= 0.0)
    {
      entry["intersection_over_union"] = m.intersectionOverUnion;
      entry["mean_surface_distance_mm"] = Number(m.meanSurfaceDistance);
    }
    methods[m.method] = entry;
  }
  j["methods"] = methods;
  j["model"] = { { "organ", settings.organ },
                 { "box_margin_mm", settings.boxMargin },
                 { "control_spacing_mm", settings.controlSpacing },
                 { "regularization", settings.regularization },
                 { "load_parameters", r.loadParameters },
                 { "surface_nodes", r.surfaceNodes },
                 { "held_nodes", r.heldNodes },
                 { "force_scale_mN", r.forceScale },
                 { "iterations", r.iterations },
                 { "youngs_modulus_kPa", r.moduli },
                 { "tetrahedra", r.state.mesh.GetNumberOfTetrahedra() },
                 { "nodes", r.state.mesh.GetNumberOfPoints() } };
  j["inverted_elements"] = r.state.invertedElements;
  j["warnings"] = r.warnings;
  j["wall_time_s"] = WallTimes(r.stages);
  return j.dump(2) + "\n";
}

std::string
IterationHistoryCsv(const std::vector<bmr::IterationRecord> & records, const std::vector<std::string> & unknownNames)
{
  std::ostringstream o;
  o << "# Phi* [mm^2] at the inner optimum; |dPhi/dp| [mm] (p: the load parameters); dPhi/dlogE [mm^2]; E "
       "[kPa]\nstage,iteration";
  for (const auto & n : unknownNames)
  {
    o << ",E_" << n << "_kPa";
  }
  o << ",phi_mm2,wall_gradient_norm_mm";
  for (const auto & n : unknownNames)
  {
    o << ",dphi_dlogE_" << n << "_mm2";
  }
  // loose: 1 when the inner solve stopped at the looser tolerance of a point the outer search passes through.
  o << ",inner_iterations,seconds,newton_iterations,factorizations,loose\n" << std::setprecision(10);
  for (const auto & r : records)
  {
    o << r.stage << "," << r.iteration;
    for (double E : r.youngsModuli)
    {
      o << "," << E;
    }
    o << "," << r.value << "," << r.wallGradientNorm;
    for (double g : r.logModulusGradient)
    {
      o << "," << g;
    }
    o << "," << r.innerIterations << "," << r.seconds << "," << r.work.newtonIterations << "," << r.work.factorizations
      << "," << (r.loose ? 1 : 0) << "\n";
  }
  return o.str();
}

namespace {
Json
LoadJson(const bmr::SceneLoad & l)
{
  if (l.type == bmr::SceneLoad::TypeEnum::Pressure)
  {
    return { { "surface", l.surface }, { "type", "pressure" }, { "pressure_kPa", l.magnitude } };
  }
  Json j = { { "surface", l.surface }, { "type", "radial_displacement" }, { "center_mm", l.center } };
  if (l.axis != std::array<double, 3>{ { 0, 0, 0 } })
  {
    j["axis"] = l.axis;
  }
  if (l.semiAxes != std::array<double, 3>{ { 0, 0, 0 } })
  {
    j["semi_axes_mm"] = l.semiAxes;
  }
  j["magnitude_mm"] = l.magnitude;
  return j;
}
} // namespace

std::string
PhantomTruthJson(const PhantomPair & pair, const PhantomSettings & settings)
{
  const bool pelvis = settings.anatomy == PhantomSettings::AnatomyEnum::Pelvis;
  Json       moduli = Json::object(), ratios = Json::object(), loads = Json::array(), landmarks = Json::array();
  for (const auto & l : pair.truthScene.labels)
  {
    if (l.role == bmr::LabelRoleEnum::Material)
    {
      moduli[l.name] = Compact(l.youngsModulus);
      ratios[l.name] = Compact(l.poissonRatio);
    }
  }
  for (const bmr::SceneLoad & l : pair.truthScene.loads)
  {
    loads.push_back(LoadJson(l));
  }
  for (std::size_t i = 0; i < pair.movingLandmarks.size(); ++i)
  {
    landmarks.push_back({ { "id", pair.movingLandmarks[i].id },
                          { "moving_mm", pair.movingLandmarks[i].point },
                          { "fixed_mm", pair.fixedLandmarks[i].point } });
  }
  Json j;
  j["units"] = { { "length", "mm" }, { "modulus", "kPa" }, { "force", "mN" } };
  j["scene"] = pelvis ? "pelvis" : "spheres";
  j["youngs_modulus_kPa"] = moduli;
  j["poisson_ratio"] = ratios;
  j["tumour_volume_fraction"] = pelvis ? settings.tumourFraction : 0.0;
  j["wall_loads"] = loads;
  // What the loads did: for pressure loads the filling (the wall's largest motion) is known only from the truth.
  Json motion = Json::object();
  for (const auto & wall : pair.wallMotionMaxMeanMM)
  {
    motion[wall.first] = { { "max", Compact(wall.second[0]) }, { "mean", Compact(wall.second[1]) } };
  }
  j["wall_motion_mm"] = motion;
  j["truth_mesh"] = { { "tetrahedra", pair.truthTetrahedra },
                      { "nodes", pair.truthNodes },
                      { "cell_size_mm", pair.truthScene.mesh.cellSize },
                      { "geometry",
                        settings.truthGeometry == PhantomSettings::TruthGeometryEnum::Anatomy ? "anatomy" : "voxels" },
                      { "refine_near_size_mm", settings.truthRefineSize }, // 0: no local refinement
                      { "refine_near_distance_mm", settings.truthRefineDistance } };
  if (pelvis)
  {
    const bmr::PelvisAnatomy & a = settings.organs;
    j["anatomy"] = { { "prostate_scale", a.prostateScale },
                     { "bladder_scale", a.bladderScale },
                     { "rectum_radius_mm", a.rectumRadius },
                     { "organ_offset_mm", a.offset } };
  }
  j["ct_noise_sigma_HU"] = settings.noiseHU;
  // The fixed grid's offset from the moving one: drawn within +- this many voxels per axis (its origin says where).
  j["fixed_grid_shift_voxels"] = settings.fixedGridShiftVoxels;
  j["landmarks"] = landmarks;
  // landmarks_tracked.csv: the fixed landmarks with this Gaussian noise per axis (a tracking system's report).
  j["tracking_noise_sigma_mm"] = settings.trackingNoiseMM;
  return j.dump(2) + "\n";
}

std::string
FormatIterationRecord(const bmr::IterationRecord & r)
{
  std::ostringstream o;
  o << "    " << std::left << std::setw(6) << r.stage << std::right << std::setw(3) << r.iteration;
  for (double E : r.youngsModuli)
  {
    o << "  E " << std::fixed << std::setprecision(2) << std::setw(8) << E << " kPa";
  }
  o << "  Phi* " << std::scientific << std::setprecision(5) << r.value << " mm^2";
  for (double g : r.logModulusGradient)
  {
    o << "  dPhi/dlogE " << std::setprecision(2) << std::setw(9) << g;
  }
  o << "  |dPhi/dp| " << std::setprecision(1) << r.wallGradientNorm << "  inner " << std::setw(4) << r.innerIterations
    << "  " << std::fixed << std::setprecision(2) << r.seconds << " s" << (r.loose ? "  (loose)" : "");
  if (r.work.newtonIterations > 0)
  {
    o << "  (" << r.work.stateSolves << " solves, " << r.work.newtonIterations << " Newton iterations, "
      << r.work.factorizations << " factorizations, " << r.work.rejectedIncrements << " halved increments, "
      << r.work.coldStarts << " cold starts)";
  }
  return o.str();
}

std::string
StageTable(const std::vector<PipelineStage> & stages)
{
  std::ostringstream o;
  o << "  stage                               wall [s]\n";
  double total = 0.0;
  for (const auto & s : stages)
  {
    o << "  " << std::left << std::setw(36) << s.name << std::right << std::fixed << std::setprecision(3)
      << std::setw(8) << s.seconds << "\n";
    total += s.seconds;
  }
  o << "  " << std::left << std::setw(36) << "total" << std::right << std::setw(8) << total << "\n";
  return o.str();
}

std::string
WallLawCaveat(const bmr::WallLoadSettings & walls)
{
  if (walls.trainedBasis)
  {
    return "the interval assumes walls that move in the trained basis (--wall-basis); its half-widths were calibrated "
           "on walls that move along their normals, so its coverage in a trained basis is not calibrated";
  }
  switch (walls.motion)
  {
    case bmr::WallMotionEnum::AlongNormals:
      return "the interval assumes walls that move along their normals (--wall-motion normal) and does not contain "
             "the wall law's influence: its coverage holds for such walls; on pressure-filled lumens it covered 7 of "
             "12 truths at 95 % and the fit was up to 2x too stiff; use --wall-motion traction there "
             "(docs/history/benchmarks.md, pressure-filled lumens)";
    case bmr::WallMotionEnum::Free:
      return "the interval assumes walls that may also slide (--wall-motion free), which read the prostate a fifth "
             "to a third too soft on walls that move along their normals (docs/history/benchmarks.md); its coverage is "
             "not "
             "calibrated";
    case bmr::WallMotionEnum::NormalTraction:
      return "the interval assumes lumens loaded by normal tractions (--wall-motion traction): on pressure-filled "
             "lumens it covered 12 of 12 truths at 95 % and 9 of 12 at 68 % with the default half-widths; such "
             "tractions cannot fit walls that move along their normals (docs/history/benchmarks.md, pressure-filled "
             "lumens)";
    case bmr::WallMotionEnum::UniformPressure:
      return "the interval assumes one uniform pressure per lumen (--wall-motion pressure); its half-widths were "
             "calibrated on walls that move along their normals: on 8 neo-Hookean pressure-filled truths it covered "
             "all 8 at 68 % and 95 %, 6 of them only as a one-sided bound or not determined "
             "(docs/history/benchmarks.md, one "
             "uniform pressure per lumen)";
  }
  return std::string();
}

std::string
UncertaintyText(const RegistrationResult & result, const std::string & label)
{
  const auto interval = result.modulusInterval.find(label);
  if (interval != result.modulusInterval.end())
  {
    return " (fit); stated: " + ModulusIntervalText(label, interval->second);
  }
  const auto it = result.modulusUncertainty.find(label);
  if (it == result.modulusUncertainty.end())
  {
    return std::string();
  }
  if (!std::isfinite(it->second))
  {
    return " (uncertainty: not determined, Phi* has no positive curvature there)";
  }
  std::ostringstream os;
  os << " (uncertainty x/ exp(" << std::setprecision(3) << it->second << "), i.e. +-" << std::setprecision(2)
     << 100.0 * it->second << " %, one standard deviation)";
  return os.str();
}

std::string
RecoveredModulusText(const RegistrationResult & result, const std::string & label)
{
  const auto interval = result.modulusInterval.find(label);
  if (interval != result.modulusInterval.end() && !interval->second.notDeterminedReason.empty())
  {
    return ModulusIntervalText(label, interval->second);
  }
  std::ostringstream os;
  os << label << " " << std::fixed << std::setprecision(1) << result.youngsModulus.at(label) << " kPa";
  return os.str() + UncertaintyText(result, label);
}

} // namespace itk

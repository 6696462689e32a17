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
// biomechreg register: joint estimation of boundary loads and elasticity (itk::RegisterSegmentedPair) and
// the displacement fields, warped images and report that come out of it.
#include "biomechregCommon.h"
#include "itkBiomechanicalReports.h"
#include "bmrWallMotionBasis.h"
#include "itkDicomRT.h"

#include <cctype>
#include <cmath>
#include <sstream>

namespace bmrcli {

/** --uncertainty rescan|bootstrap|curvature|none, --resamples N, --uncertainty-seed S, --uncertainty-threads T. */
void
ParseUncertaintySettings(const Arguments & args, itk::UncertaintySettings & u)
{
  const std::string method = args.Choice("--uncertainty", { "rescan", "bootstrap", "curvature", "none" });
  u.method = method == "rescan"      ? itk::UncertaintyMethodEnum::Rescan
             : method == "bootstrap" ? itk::UncertaintyMethodEnum::Bootstrap
             : method == "curvature" ? itk::UncertaintyMethodEnum::Curvature
                                     : itk::UncertaintyMethodEnum::None;
  u.resamples = args.Count("--resamples", u.resamples, 3, 1000);
  u.seed = args.Count("--uncertainty-seed", static_cast<unsigned int>(u.seed), 0, 4000000000u);
  if (args.Has("--uncertainty-threads")) // else 0: as many as --threads
  {
    u.threads = args.Count("--uncertainty-threads", 1, 1, 64);
  }
  u.correctBias = args.Choice("--uncertainty-bias-correction", { "off", "on" }) == "on";
  u.warmStart = args.Choice("--uncertainty-warm-start", { "on", "off" }) == "on";
  u.quantiles = args.Choice("--uncertainty-quantiles", { "calibrated", "student" }) == "student"
                  ? itk::IntervalQuantilesEnum::Student
                  : itk::IntervalQuantilesEnum::Calibrated;
  u.statedVoxelLimitMM = args.Number("--uncertainty-voxel-limit-mm", u.statedVoxelLimitMM);
  // What the resamples vary (UncertaintySettings; their ranges: UncertaintySettings::Validate).
  const std::pair<const char *, double *> scales[] = { { "--uncertainty-mesh-jitter", &u.meshJitter },
                                                       { "--uncertainty-shift-voxels", &u.shiftVoxels },
                                                       { "--uncertainty-rotation-deg", &u.rotationDegrees },
                                                       { "--uncertainty-wall-slip", &u.tangentialWallFraction },
                                                       { "--uncertainty-smoothing-voxels", &u.smoothingVoxels },
                                                       { "--uncertainty-step-tolerance", &u.stepTolerance },
                                                       { "--uncertainty-simulation-mesh-scale",
                                                         &u.simulationMeshScale } };
  for (const auto & [key, value] : scales)
  {
    *value = args.Number(key, *value);
  }
}

/** \a description of a settings struct's refusal (RegistrationSettings::Validate) with each setting it names
 * replaced by the option that sets it. */
std::string
InOptionNames(std::string description)
{
  static const std::pair<const char *, const char *> options[] = {
    { "coarseFactor", "--coarse-factor" },
    { "meshScale", "--mesh-scale" },
    { "controlSpacing", "--wall-spacing-mm" },
    { "regularization", "--wall-regularization" },
    { "basisModes", "--basis-modes" },
    { "basisPriorWeight", "--basis-prior-weight" },
    { "outerGradientTolerance", "--outer-tolerance" },
    { "limitElementInversion", "--element-inversion limit" },
    { "resamples", "--resamples" },
    { "meshJitter", "--uncertainty-mesh-jitter" },
    { "shiftVoxels", "--uncertainty-shift-voxels" },
    { "rotationDegrees", "--uncertainty-rotation-deg" },
    { "tangentialWallFraction", "--uncertainty-wall-slip" },
    { "smoothingVoxels", "--uncertainty-smoothing-voxels" },
    { "stepTolerance", "--uncertainty-step-tolerance" },
    { "simulationMeshScale", "--uncertainty-simulation-mesh-scale" },
    { "statedVoxelLimitMM", "--uncertainty-voxel-limit-mm" }
  };
  const auto isWordChar = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; };
  for (const auto & [setting, option] : options)
  {
    const std::string name(setting);
    for (std::size_t at = description.find(name); at != std::string::npos; at = description.find(name, at + 1))
    {
      const std::size_t end = at + name.size();
      if ((at == 0 || !isWordChar(description[at - 1])) && (end == description.size() || !isWordChar(description[end])))
      {
        description.replace(at, name.size(), option);
      }
    }
  }
  return description;
}

/** --fixed-probabilities prostate=p.nrrd,bladder=b.nrrd: one probability image per organ (empty: none). */
itk::OrganProbabilityImages
ReadProbabilityImages(const std::string & list)
{
  itk::OrganProbabilityImages images;
  std::stringstream           items(list);
  for (std::string item; std::getline(items, item, ',');)
  {
    const auto equals = item.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == item.size())
    {
      throw UsageError("--fixed-probabilities takes ORGAN=FILE pairs separated by commas, got \"" + item + "\"");
    }
    const std::string organ = item.substr(0, equals);
    images[organ] =
      ReadImage<itk::BiomechanicalProbabilityImageType>(item.substr(equals + 1), "fixed probability of " + organ);
  }
  return images;
}

/** The objective organs of an RTSTRUCT given as \a fixedLabels as the area fractions of their outlines
 * (itk::ReadRTStructAreaFractions) on the fixed CT's grid, added to \a probabilities where an organ has none; nothing
 * for a label image. The fixed organs' surfaces then follow the polygons, not their voxels. An organ's ROI is named
 * as the organ unless \a roiOfOrgan says otherwise (a structure set's TG-263 names). */
void
AddOutlineFractions(const std::string &                        fixedLabels,
                    const itk::ImageBase<3> *                  fixedCT,
                    const bmr::Scene &                         scene,
                    const std::map<std::string, std::string> & roiOfOrgan,
                    itk::OrganProbabilityImages &              probabilities)
{
  if (itk::ReadDicomModality(fixedLabels) != "RTSTRUCT")
  {
    return;
  }
  std::vector<std::string> organs, rois;
  for (const bmr::ObjectiveTerm & term : scene.objective)
  {
    if (probabilities.count(term.label) == 0)
    {
      organs.push_back(term.label);
      rois.push_back(roiOfOrgan.count(term.label) ? roiOfOrgan.at(term.label) : term.label);
    }
  }
  if (organs.empty())
  {
    return; // every objective organ has a probability image of its own
  }
  try
  {
    const auto fractions = itk::ReadRTStructAreaFractions(fixedLabels, fixedCT, rois);
    for (std::size_t i = 0; i < organs.size(); ++i)
    {
      probabilities[organs[i]] = fractions.at(rois[i]);
    }
  }
  catch (const itk::ExceptionObject & e)
  {
    bmr::Fail("AddOutlineFractions", "fixed label image: " + std::string(e.GetDescription()));
  }
  std::string names;
  for (const auto & organ : organs)
  {
    names += " " + organ;
  }
  PrintLine("  fixed organs' surfaces from the RTSTRUCT's outlines:" + names);
}

/** --wall-basis FILE (a trained basis of wall motion, `biomechreg train-basis`), --basis-modes K (0: all) and
 * --basis-prior-weight W [mm^2]. */
void
ParseWallBasis(const Arguments & args, bmr::WallLoadSettings & walls)
{
  if (!args.Has("--wall-basis"))
  {
    for (const char * option : { "--basis-modes", "--basis-prior-weight" })
    {
      if (args.Has(option))
      {
        throw UsageError(std::string(option) + " needs --wall-basis FILE");
      }
    }
    return;
  }
  walls.trainedBasis = std::make_shared<const bmr::WallMotionBasis>(bmr::ReadWallMotionBasis(args.Get("--wall-basis")));
  walls.basisModes = args.Count("--basis-modes", 0, 0, 1000000);
  walls.basisPriorWeight = args.Number("--basis-prior-weight", walls.basisPriorWeight);
}

itk::RegistrationSettings
ParseRegistrationSettings(const Arguments & args)
{
  itk::RegistrationSettings s;
  bmr::EstimatorSettings &  e = s.estimator;
  e.numberOfSweepSamples = args.Count("--sweep-samples", e.numberOfSweepSamples, 3, 100);
  s.coarseFactor = args.Number("--coarse-factor", s.coarseFactor);
  s.walls.controlSpacing = args.Number("--wall-spacing-mm", s.walls.controlSpacing);
  const std::string motion = args.Choice("--wall-motion", { "normal", "free", "traction", "pressure" });
  s.walls.motion = motion == "normal"     ? bmr::WallMotionEnum::AlongNormals
                   : motion == "free"     ? bmr::WallMotionEnum::Free
                   : motion == "traction" ? bmr::WallMotionEnum::NormalTraction
                                          : bmr::WallMotionEnum::UniformPressure;
  for (const char * option : { "--wall-spacing-mm", "--wall-regularization" })
  {
    if (motion == "pressure" && args.Has(option))
    {
      throw UsageError(std::string(option) + " does not apply to --wall-motion pressure (one pressure per wall)");
    }
  }
  s.walls.regularization = args.Number("--wall-regularization", s.walls.regularization);
  ParseWallBasis(args, s.walls);
  e.limitElementInversion = args.Choice("--element-inversion", { "allow", "limit" }) == "limit";
  s.meshScale = args.Number("--mesh-scale", s.meshScale);
  s.interpolateSlices = args.Choice("--slice-interpolation", { "off", "on" }) == "on";
  ParseUncertaintySettings(args, s.uncertainty);
  e.maximumOuterIterations = args.Count("--max-outer-iterations", e.maximumOuterIterations, 1, 1000);
  e.outerGradientTolerance = args.Number("--outer-tolerance", e.outerGradientTolerance);
  // The ranges are the library's (one place); out of range is a usage error here, as a wrong option is.
  try
  {
    s.Validate();
  }
  catch (const itk::ExceptionObject & e)
  {
    throw UsageError(InOptionNames(e.GetDescription()));
  }
  return s;
}

itk::RegistrationOutputs
ParseRegistrationOutputs(const Arguments & args)
{
  itk::RegistrationOutputs o;
  try
  {
    o = itk::RegistrationOutputs::Parse(args.Get("--outputs", "default"));
  }
  catch (const itk::ExceptionObject & e)
  {
    throw UsageError(std::string("--outputs: ") + e.GetDescription());
  }
  o.doubleFields = args.Choice("--field-precision", { "float", "double" }) == "double";
  if (args.Has("--compression-level")) // else label maps at 1, fields and CT uncompressed
  {
    o.compressionLevel = static_cast<int>(args.Count("--compression-level", 1, 0, 9));
  }
  return o;
}

void
WriteRegistration(const std::string &               out,
                  const itk::RegistrationResult &   result,
                  const itk::RegistrationSettings & settings,
                  const itk::RegistrationOutputs &  outputs,
                  StageTimer &                      timer)
{
  timer.StageBegin("write outputs");
  timer.stages.push_back(itk::WriteRegistrationOutputs(out, result, settings, timer.stages, outputs));
  timer.StageEnd("write outputs", timer.stages.back().seconds, "");
}

void
PrintOuterIterations(const itk::RegistrationResult & result)
{
  for (const auto & r : result.estimation.outerIterations)
  {
    std::cout << "    outer " << std::setw(3) << r.iteration << "  E";
    for (double E : r.youngsModuli)
    {
      std::cout << " " << std::fixed << std::setprecision(2) << E << " kPa";
    }
    std::cout << "  Phi* " << std::scientific << std::setprecision(6) << r.value << std::endl;
  }
  if (!result.estimation.outerStopCondition.empty())
  {
    std::cout << "    outer stop: " << result.estimation.outerStopCondition << std::endl;
  }
}

int
RegisterCommand(const Arguments & args)
{
  const std::string       movingCT = args.Require("--moving-ct");
  const std::string       movingLabels = args.Require("--moving-labels");
  const std::string       fixedCT = args.Require("--fixed-ct");
  const std::string       fixedLabels = args.Require("--fixed-labels");
  const std::string       out = args.Require("--out");
  const RegistrationPaths paths{ movingLabels,
                                 fixedLabels,
                                 args.Get("--scene"),
                                 args.Get("--roi-map"),
                                 out,
                                 args.Get("--moving-label-names"),
                                 args.Get("--fixed-label-names") };
  const auto              outputs = ParseRegistrationOutputs(args);
  auto                    settings = ParseRegistrationSettings(args);
  settings.pushField = outputs.forwardField; // computed only when written
  settings.elementState = outputs.mesh;
  const std::string probabilities = args.Get("--fixed-probabilities");
  const bool        ignoreROIs = IgnoreUnmappedROIs(args);
  const std::string labelSurfaces =
    args.Has("--label-surfaces") ? args.Choice("--label-surfaces", { "voxels", "distance" }) : "";
  const bool outlines = args.Choice("--rtstruct-surfaces", { "outlines", "voxels" }) == "outlines";
  args.CheckAllUsed();

  StageTimer timer(true);
  std::cout << "biomechreg register -> " << out << std::endl;
  timer.Begin("read inputs");
  // A label input may be an RTSTRUCT, rasterized on the grid of the CT of the same scan; the fixed CT is read to
  // check it (and to grid an RTSTRUCT); the fixed label image defines the output grid.
  const auto   moving = ReadImage<CTImageType>(movingCT, "moving CT");
  const auto   fixed = ReadImage<CTImageType>(fixedCT, "fixed CT");
  auto         anatomy = ReadRegistrationAnatomy(paths, moving, fixed, ignoreROIs);
  bmr::Scene & scene = anatomy.scene;
  if (!labelSurfaces.empty())
  {
    scene.mesh.labelSurfaces = labelSurfaces == "distance" ? bmr::MeshingParameters::LabelSurfaces::Distance
                                                           : bmr::MeshingParameters::LabelSurfaces::Voxels;
  }
  auto fixedProbabilities = ReadProbabilityImages(probabilities);
  if (outlines)
  {
    AddOutlineFractions(fixedLabels, fixed, scene, anatomy.fixedROIOfOrgan, fixedProbabilities);
  }
  timer.End();
  // The moving CT is warped only when the warped CT is written.
  const auto result = itk::RegisterSegmentedPair(anatomy.movingLabels,
                                                 anatomy.fixedLabels,
                                                 fixedProbabilities,
                                                 outputs.warpedCT ? moving : nullptr,
                                                 scene,
                                                 settings,
                                                 &timer);
  timer.stages.insert(timer.stages.end(), result.state.stages.begin(), result.state.stages.end());
  WriteRegistration(out, result, settings, outputs, timer);

  PrintOuterIterations(result);
  std::cout << "\n  recovered Young's moduli:";
  for (const auto & kv : result.youngsModulus)
  {
    std::cout << "  " << itk::RecoveredModulusText(result, kv.first);
  }
  if (!result.modulusInterval.empty())
  {
    std::cout << "\n  note: " << itk::WallLawCaveat(settings.walls);
  }
  if (!result.estimation.identifiable)
  {
    std::cout << "\n  warning: " << result.estimation.identifiabilityMessage;
  }
  std::cout << std::endl;
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

} // namespace bmrcli

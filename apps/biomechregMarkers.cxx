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
// biomechreg markers: the treatment anatomy from tracked implanted markers (itk::EstimateTreatmentFromMarkers).
#include "biomechregCommon.h"

#include "itkMarkerPipeline.h"

namespace bmrcli {
namespace {
itk::MarkerSettings
ParseMarkerSettings(const Arguments & args)
{
  itk::MarkerSettings s;
  s.organ = args.Get("--organ", s.organ);
  s.boxMargin = args.Number("--box-margin-mm", s.boxMargin);
  s.controlSpacing = args.Number("--control-spacing-mm", s.controlSpacing);
  s.regularization = args.Number("--regularization", s.regularization);
  s.meshScale = args.Number("--mesh-scale", s.meshScale);
  if (!(s.boxMargin > 0.0 && s.boxMargin <= 200.0) || !(s.controlSpacing > 0.0 && s.controlSpacing <= 100.0) ||
      !(s.regularization >= 0.0) || !(s.meshScale >= 0.2 && s.meshScale <= 5.0))
  {
    throw UsageError("--box-margin-mm must lie in (0, 200], --control-spacing-mm in (0, 100], --regularization >= 0 "
                     "and --mesh-scale in [0.2, 5]");
  }
  s.moduli = args.NamedNumbers("--modulus");
  const std::string leaveOneOut = args.Get("--leave-one-out", "on");
  if (leaveOneOut != "on" && leaveOneOut != "off")
  {
    throw UsageError("--leave-one-out must be on or off");
  }
  s.leaveOneOut = leaveOneOut == "on";
  return s;
}

void
PrintMethods(const itk::MarkerResult & r)
{
  std::cout << "\n  method   fit max [mm]   leave-one-out RMS [mm]   IoU      D [mm]"
            << (r.methods.empty() || r.methods[0].leaveOneOutTrueRms < 0.0 ? "" : "   leave-one-out vs truth [mm]")
            << "\n";
  for (const auto & m : r.methods)
  {
    double fit = 0.0;
    for (double d : m.fitResidual)
    {
      fit = std::max(fit, d);
    }
    std::cout << "  " << std::left << std::setw(8) << m.method << std::right << std::fixed << std::setprecision(3)
              << std::setw(13) << fit << std::setw(25) << m.leaveOneOutRms;
    if (m.intersectionOverUnion >= 0.0)
    {
      std::cout << std::setw(9) << m.intersectionOverUnion << std::setw(10) << m.meanSurfaceDistance;
    }
    if (m.leaveOneOutTrueRms >= 0.0)
    {
      std::cout << std::setw(m.intersectionOverUnion >= 0.0 ? 30 : 49) << m.leaveOneOutTrueRms;
    }
    std::cout << "\n";
  }
}
} // namespace

int
MarkersCommand(const Arguments & args)
{
  const std::string ctPath = args.Require("--planning-ct");
  const std::string labelsPath = args.Require("--planning-labels");
  const std::string scenePath = args.Require("--scene");
  const std::string planningMarkersPath = args.Require("--planning-markers");
  const std::string treatmentMarkersPath = args.Require("--treatment-markers");
  const std::string treatmentLabelsPath = args.Get("--treatment-labels");
  const std::string trueMarkersPath = args.Get("--true-treatment-markers");
  const std::string out = args.Require("--out");
  const auto        settings = ParseMarkerSettings(args);
  const bool        ignoreROIs = IgnoreUnmappedROIs(args);
  args.CheckAllUsed();

  StageTimer timer;
  std::cout << "biomechreg markers -> " << out << std::endl;
  timer.Begin("read inputs");
  const bmr::Scene scene = bmr::ReadScene(scenePath);
  const auto       ct = ReadImage<CTImageType>(ctPath, "planning CT");
  const auto       labels = ReadLabelsOrRTStruct(labelsPath, "planning label image", ct, scene, ignoreROIs);
  const auto       planningMarkers = bmr::ReadLandmarks(planningMarkersPath);
  const auto       treatmentMarkers = bmr::ReadLandmarks(treatmentMarkersPath);
  // A phantom's noise-free treatment markers (evaluation only): read now, so that a bad file fails before the fit.
  const auto trueMarkers = trueMarkersPath.empty() ? std::vector<bmr::Landmark>() : bmr::ReadLandmarks(trueMarkersPath);
  // Real treatment labels (for the evaluation only) lie on the planning grid; an RTSTRUCT is gridded there.
  LabelImageType::Pointer treatmentLabels;
  if (!treatmentLabelsPath.empty())
  {
    treatmentLabels = ReadLabelsOrRTStruct(treatmentLabelsPath, "treatment label image", ct, scene, ignoreROIs);
  }
  timer.End();
  auto result =
    itk::EstimateTreatmentFromMarkers(labels, ct, scene, planningMarkers, treatmentMarkers, settings, &timer);
  timer.stages.insert(timer.stages.end(), result.stages.begin(), result.stages.end());
  if (treatmentLabels)
  {
    timer.Begin("evaluation against the treatment labels (IoU, D)");
    itk::EvaluateMarkerMethods(result, treatmentLabels, scene.FindLabel(settings.organ)->value);
    timer.End();
  }
  if (!trueMarkersPath.empty())
  {
    itk::EvaluateLeaveOneOutAgainstTruth(result, trueMarkers);
    if (result.methods.empty() || result.methods[0].leaveOneOutTrueRms < 0.0)
    {
      PrintWarning("--true-treatment-markers is not used: leave-one-out is off or there are fewer than 3 markers");
    }
  }
  timer.Begin("write outputs");
  MakeOutputDirectory(out);
  itk::WriteImageAtomically(result.state.pullBack.GetPointer(), out + "/field.nrrd");
  itk::WriteImageAtomically(result.warpedCT.GetPointer(), out + "/warped_ct.nrrd");
  for (const auto & m : result.methods)
  {
    // The FEM's estimate is warped_labels.nrrd; the references' are written beside it for comparison.
    if (m.method == "fem")
    {
      itk::WriteImageAtomically(m.warpedLabels.GetPointer(), out + "/warped_labels.nrrd");
    }
    else if (m.method != "none")
    {
      itk::WriteImageAtomically(m.warpedLabels.GetPointer(), out + "/warped_labels_" + m.method + ".nrrd");
    }
  }
  timer.End();
  result.stages = timer.stages;
  bmr::WriteTextFileAtomically(out + "/report.json", itk::MarkerReportJson(result, settings));
  PrintMethods(result);
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

} // namespace bmrcli

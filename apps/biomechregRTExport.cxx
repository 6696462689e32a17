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
// biomechreg rt-export: a label map as a DICOM RTSTRUCT and a dose as a DICOM RTDOSE, in the frame of reference
// of a DICOM image series (itkDicomRTWriters.h): registered structures and doses back to a planning system.
#include "biomechregCommon.h"
#include "itkDicomRT.h"
#include "itkDicomRTWriters.h"

#include <filesystem>
#include <iostream>

namespace bmrcli {

int
RTExportCommand(const Arguments & args)
{
  const std::string reference = args.Require("--reference-ct");
  const std::string labelsPath = args.Get("--labels");
  const std::string scenePath = args.Get("--scene");
  const std::string rtstructPath = args.Get("--rtstruct-out");
  const std::string dosePath = args.Get("--dose");
  const std::string rtdosePath = args.Get("--rtdose-out");
  const std::string planUID = args.Get("--plan-uid");
  args.CheckAllUsed();
  const bool structures = !labelsPath.empty() || !scenePath.empty() || !rtstructPath.empty();
  const bool dose = !dosePath.empty() || !rtdosePath.empty() || !planUID.empty();
  if (!structures && !dose)
  {
    throw UsageError("give --labels FILE --scene FILE --rtstruct-out FILE, --dose FILE --rtdose-out FILE, or both");
  }
  if (structures && (labelsPath.empty() || scenePath.empty() || rtstructPath.empty()))
  {
    throw UsageError("an RTSTRUCT needs --labels FILE, --scene FILE (the ROI names) and --rtstruct-out FILE");
  }
  if (dose && (dosePath.empty() || rtdosePath.empty()))
  {
    throw UsageError("an RTDOSE needs --dose FILE (an RTDOSE or an image in Gy) and --rtdose-out FILE");
  }

  // Everything is read and checked before anything is written.
  StageTimer timer;
  std::cout << "biomechreg rt-export (reference series " << reference << ")" << std::endl;
  timer.Begin("read inputs");
  std::map<std::int32_t, std::string> names;
  LabelImageType::Pointer             labels;
  if (structures)
  {
    names = itk::SceneROINames(bmr::ReadScene(scenePath));
    labels = ReadImage<LabelImageType>(labelsPath, "label image");
  }
  const itk::DicomRTDoseImageType::Pointer doseImage = dose ? itk::ReadDoseImage(dosePath) : nullptr;
  timer.End();
  for (const std::string & path : { rtstructPath, rtdosePath })
  {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!path.empty() && !parent.empty())
    {
      std::filesystem::create_directories(parent);
    }
  }
  if (structures)
  {
    timer.Begin("RTSTRUCT");
    itk::WriteRTStruct(labels, names, reference, rtstructPath);
    timer.End(rtstructPath);
  }
  if (dose)
  {
    timer.Begin("RTDOSE");
    itk::WriteRTDose(doseImage, reference, rtdosePath, planUID);
    timer.End(rtdosePath);
  }
  return 0;
}

} // namespace bmrcli

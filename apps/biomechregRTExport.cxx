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
// of a DICOM image series (itkDicomRTWriters.h): registered structures and doses back to a planning system; the
// field as a DICOM Deformable Spatial Registration between the fixed and the moving series.
#include "biomechregCommon.h"
#include "itkDicomRT.h"
#include "itkDicomRTWriters.h"

#include <filesystem>
#include <iostream>

namespace bmrcli {

namespace {
/** What rt-export was asked to write; every group complete or absent. */
struct RTExportRequest
{
  std::string reference, labelsPath, scenePath, rtstructPath, dosePath, rtdosePath, planUID;
  std::string fieldPath, movingSeries, registrationPath;
  bool        structures{ false }, dose{ false }, registration{ false };
};

RTExportRequest
ParseRTExport(const Arguments & args)
{
  RTExportRequest r;
  r.reference = args.Require("--reference-ct");
  r.labelsPath = args.Get("--labels");
  r.scenePath = args.Get("--scene");
  r.rtstructPath = args.Get("--rtstruct-out");
  r.dosePath = args.Get("--dose");
  r.rtdosePath = args.Get("--rtdose-out");
  r.planUID = args.Get("--plan-uid");
  r.fieldPath = args.Get("--field");
  r.movingSeries = args.Get("--moving-ct");
  r.registrationPath = args.Get("--registration-out");
  args.CheckAllUsed();
  r.structures = !r.labelsPath.empty() || !r.scenePath.empty() || !r.rtstructPath.empty();
  r.dose = !r.dosePath.empty() || !r.rtdosePath.empty() || !r.planUID.empty();
  r.registration = !r.fieldPath.empty() || !r.movingSeries.empty() || !r.registrationPath.empty();
  if (!r.structures && !r.dose && !r.registration)
  {
    throw UsageError("give --labels FILE --scene FILE --rtstruct-out FILE, --dose FILE --rtdose-out FILE, "
                     "--field FILE --moving-ct DIR --registration-out FILE, or several");
  }
  if (r.structures && (r.labelsPath.empty() || r.scenePath.empty() || r.rtstructPath.empty()))
  {
    throw UsageError("an RTSTRUCT needs --labels FILE, --scene FILE (the ROI names) and --rtstruct-out FILE");
  }
  if (r.dose && (r.dosePath.empty() || r.rtdosePath.empty()))
  {
    throw UsageError("an RTDOSE needs --dose FILE (an RTDOSE or an image in Gy) and --rtdose-out FILE");
  }
  if (r.registration && (r.fieldPath.empty() || r.movingSeries.empty() || r.registrationPath.empty()))
  {
    throw UsageError("a registration object needs --field FILE (fixed -> moving, mm), --moving-ct DIR (the moving "
                     "scan's DICOM series) and --registration-out FILE");
  }
  return r;
}
} // namespace

int
RTExportCommand(const Arguments & args)
{
  const RTExportRequest r = ParseRTExport(args);
  // Everything is read and checked before anything is written.
  StageTimer timer;
  std::cout << "biomechreg rt-export (reference series " << r.reference << ")" << std::endl;
  timer.Begin("read inputs");
  std::map<std::int32_t, std::string> names;
  LabelImageType::Pointer             labels;
  if (r.structures)
  {
    names = itk::SceneROINames(bmr::ReadScene(r.scenePath));
    labels = ReadImage<LabelImageType>(r.labelsPath, "label image");
  }
  const itk::DicomRTDoseImageType::Pointer doseImage = r.dose ? itk::ReadDoseImage(r.dosePath) : nullptr;
  const FieldType::Pointer field = r.registration ? ReadImage<FieldType>(r.fieldPath, "displacement field") : nullptr;
  timer.End();
  for (const std::string & path : { r.rtstructPath, r.rtdosePath, r.registrationPath })
  {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    if (!path.empty() && !parent.empty())
    {
      std::filesystem::create_directories(parent);
    }
  }
  if (r.structures)
  {
    timer.Begin("RTSTRUCT");
    itk::WriteRTStruct(labels, names, r.reference, r.rtstructPath);
    timer.End(r.rtstructPath);
  }
  if (r.dose)
  {
    timer.Begin("RTDOSE");
    itk::WriteRTDose(doseImage, r.reference, r.rtdosePath, r.planUID);
    timer.End(r.rtdosePath);
  }
  if (r.registration)
  {
    timer.Begin("deformable registration (REG)");
    itk::WriteDeformableSpatialRegistration(field, r.reference, r.movingSeries, r.registrationPath);
    timer.End(r.registrationPath);
  }
  return 0;
}

} // namespace bmrcli

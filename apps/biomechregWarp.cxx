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
// biomechreg warp: an image resampled through a fixed -> moving displacement field (itk::ImageWarper).
#include "biomechregCommon.h"
#include "itkDicomRT.h"

namespace bmrcli {
namespace {
/** The field of an image file, or of a DICOM Deformable Spatial Registration object (modality REG). */
FieldType::Pointer
ReadField(const std::string & path)
{
  if (itk::ReadDicomModality(path) == "REG")
  {
    return itk::ReadDeformableSpatialRegistration(path).field;
  }
  return ReadImage<FieldType>(path, "displacement field");
}
} // namespace

int
WarpCommand(const Arguments & args)
{
  const std::string imagePath = args.Require("--image");
  const std::string fieldPath = args.Require("--field");
  const std::string out = args.Require("--out");
  const bool        labels = args.Choice("--labels", { "off", "on" }) == "on";
  const double      outside = args.Number("--outside", labels ? 0.0 : -1000.0);
  args.CheckAllUsed();

  StageTimer timer;
  std::cout << "biomechreg warp -> " << out << "/warped.nrrd" << std::endl;
  timer.Begin("read inputs");
  const auto field = ReadField(fieldPath);
  timer.End();
  MakeOutputDirectory(out);
  timer.Begin(labels ? "warp (nearest neighbour)" : "warp (linear)");
  if (labels)
  {
    const auto image = ReadImage<LabelImageType>(imagePath, "label image");
    const auto warped =
      itk::WarpImage(image.GetPointer(), field.GetPointer(), true, static_cast<std::int32_t>(outside));
    itk::WriteImageAtomically(warped.GetPointer(), out + "/warped.nrrd");
  }
  else
  {
    const auto image = ReadImage<CTImageType>(imagePath, "image");
    const auto warped = itk::WarpImage(image.GetPointer(), field.GetPointer(), false, static_cast<float>(outside));
    itk::WriteImageAtomically(warped.GetPointer(), out + "/warped.nrrd");
  }
  timer.End();
  PrintTimings(timer.stages);
  return EXIT_SUCCESS;
}

} // namespace bmrcli

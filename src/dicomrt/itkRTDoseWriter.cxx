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
// WriteRTDose: a dose image [Gy] as a DICOM RT Dose in the frame of reference of an image series.
#include "itkDicomRTWriters.h"

#include "bmrError.h"
#include "itkDicomRTCommon.h"
#include "itkImageRegionConstIteratorWithIndex.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace itk {
namespace {
constexpr const char * Where = "WriteRTDose";
constexpr const char * RTDoseStorage = "1.2.840.10008.5.1.4.1.1.481.2";
constexpr const char * RTPlanStorage = "1.2.840.10008.5.1.4.1.1.481.5";

/** The largest dose [Gy]; fails on a negative or non-finite one, naming the voxel. */
double
MaximumDose(const DicomRTDoseImageType * dose)
{
  double maximum = 0.0;
  for (ImageRegionConstIteratorWithIndex<DicomRTDoseImageType> it(dose, dose->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it)
  {
    if (!(std::isfinite(it.Get()) && it.Get() >= 0.0f))
    {
      std::ostringstream os;
      os << "the dose at voxel " << it.GetIndex() << " is " << it.Get() << " Gy; a dose must be finite and >= 0";
      bmr::Fail(Where, os.str());
    }
    maximum = std::max(maximum, double(it.Get()));
  }
  return maximum;
}

/** The frames' offsets along the row x column normal [mm], relative to the first frame. */
std::vector<double>
FrameOffsets(const DicomRTDoseImageType * dose)
{
  const int sense = dicomrt::SliceAxisSense(dose->GetDirection());
  if (sense == 0)
  {
    bmr::Fail(Where, "the dose grid's slices are not perpendicular to its rows and columns (an oblique frame stack)");
  }
  std::vector<double> offsets;
  for (SizeValueType k = 0; k < dose->GetLargestPossibleRegion().GetSize(2); ++k)
  {
    offsets.push_back(sense * double(k) * dose->GetSpacing()[2]);
  }
  return offsets;
}

/** The Image Plane, Image Pixel and Multi-frame modules of \a dose's grid. */
void
PutGrid(gdcm::DataSet & ds, const DicomRTDoseImageType * dose)
{
  const auto &     region = dose->GetLargestPossibleRegion();
  const auto &     D = dose->GetDirection();
  const double     orientation[6] = { D(0, 0), D(1, 0), D(2, 0), D(0, 1), D(1, 1), D(2, 1) };
  Point<double, 3> origin;
  dose->TransformIndexToPhysicalPoint(region.GetIndex(), origin);
  const double              spacing[2] = { dose->GetSpacing()[1], dose->GetSpacing()[0] }; // rows, then columns
  const std::vector<double> offsets = FrameOffsets(dose);
  dicomrt::Put(ds, gdcm::Tag(0x0020, 0x0032), gdcm::VR::DS, dicomrt::DecimalStrings(origin.GetDataPointer(), 3));
  dicomrt::Put(ds, gdcm::Tag(0x0020, 0x0037), gdcm::VR::DS, dicomrt::DecimalStrings(orientation, 6));
  dicomrt::Put(ds, gdcm::Tag(0x0028, 0x0030), gdcm::VR::DS, dicomrt::DecimalStrings(spacing, 2));
  dicomrt::Put(ds, gdcm::Tag(0x0018, 0x0050), gdcm::VR::DS, dicomrt::DecimalString(dose->GetSpacing()[2]));
  const auto us = [&ds](std::uint16_t tagElement, std::uint16_t value) {
    gdcm::DataElement element(gdcm::Tag(0x0028, tagElement));
    element.SetVR(gdcm::VR::US);
    element.SetByteValue(reinterpret_cast<const char *>(&value), 2);
    ds.Replace(element);
  };
  us(0x0002, 1); // US values are binary
  us(0x0010, static_cast<std::uint16_t>(region.GetSize(1)));
  us(0x0011, static_cast<std::uint16_t>(region.GetSize(0)));
  us(0x0100, 32);
  us(0x0101, 32);
  us(0x0102, 31);
  us(0x0103, 0);
  dicomrt::Put(ds, gdcm::Tag(0x0028, 0x0004), gdcm::VR::CS, "MONOCHROME2");
  dicomrt::Put(ds, gdcm::Tag(0x0028, 0x0008), gdcm::VR::IS, std::to_string(region.GetSize(2)));
  const std::uint16_t pointer[2] = { 0x3004, 0x000c }; // Frame Increment Pointer: the Grid Frame Offset Vector
  gdcm::DataElement   increment(gdcm::Tag(0x0028, 0x0009));
  increment.SetVR(gdcm::VR::AT);
  increment.SetByteValue(reinterpret_cast<const char *>(pointer), 4);
  ds.Replace(increment);
  dicomrt::Put(ds, gdcm::Tag(0x3004, 0x000c), gdcm::VR::DS, dicomrt::DecimalStrings(offsets.data(), offsets.size()));
}

/** The dose as 32-bit unsigned values of \a scaling Gy each, frame after frame. */
std::vector<std::uint32_t>
QuantizedDose(const DicomRTDoseImageType * dose, double scaling)
{
  std::vector<std::uint32_t> values;
  values.reserve(dose->GetLargestPossibleRegion().GetNumberOfPixels());
  for (ImageRegionConstIteratorWithIndex<DicomRTDoseImageType> it(dose, dose->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it)
  {
    const double v = std::round(double(it.Get()) / scaling);
    values.push_back(static_cast<std::uint32_t>(std::min(v, double(std::numeric_limits<std::uint32_t>::max()))));
  }
  return values;
}
} // namespace

void
WriteRTDose(const DicomRTDoseImageType * dose,
            const std::string &          referenceSeries,
            const std::string &          path,
            const std::string &          referencedPlanUID)
{
  if (dose == nullptr)
  {
    bmr::Fail(Where, "no dose image");
  }
  const double                    maximum = MaximumDose(dose);
  const dicomrt::ReferencedSeries series = dicomrt::ReadReferencedSeries(referenceSeries, Where);
  // The scaling as the file states it, so that stored value x stated scaling is within half a step of the dose.
  const std::string scalingText = dicomrt::DecimalString(
    maximum > 0.0 ? maximum / double(std::numeric_limits<std::uint32_t>::max()) * (1 + 1e-9) : 1.0);
  const double                     scaling = std::stod(scalingText);
  const std::vector<std::uint32_t> values = QuantizedDose(dose, scaling);

  gdcm::DataSet ds;
  PutGrid(ds, dose);
  std::uint64_t checksum = 1469598103934665603ULL; // the contents, for the derived UIDs
  for (std::uint32_t v : values)
  {
    checksum = (checksum ^ v) * 1099511628211ULL;
  }
  dicomrt::PutCommonModules(ds,
                            series,
                            RTDoseStorage,
                            "RTDOSE",
                            std::to_string(checksum) + " " + dicomrt::StringValue(ds, gdcm::Tag(0x0020, 0x0032)) + " " +
                              scalingText);
  dicomrt::Put(ds, gdcm::Tag(0x0020, 0x0013), gdcm::VR::IS, "1");
  dicomrt::Put(ds, gdcm::Tag(0x3004, 0x0002), gdcm::VR::CS, "GY");
  dicomrt::Put(ds, gdcm::Tag(0x3004, 0x0004), gdcm::VR::CS, "PHYSICAL");
  dicomrt::Put(ds, gdcm::Tag(0x3004, 0x000a), gdcm::VR::CS, "PLAN");
  dicomrt::Put(ds, gdcm::Tag(0x3004, 0x000e), gdcm::VR::DS, scalingText);
  if (!referencedPlanUID.empty())
  {
    gdcm::DataSet plan;
    dicomrt::Put(plan, gdcm::Tag(0x0008, 0x1150), gdcm::VR::UI, RTPlanStorage);
    dicomrt::Put(plan, gdcm::Tag(0x0008, 0x1155), gdcm::VR::UI, referencedPlanUID);
    dicomrt::PutSequence(ds, gdcm::Tag(0x300c, 0x0002), { plan });
  }
  gdcm::DataElement pixels(gdcm::Tag(0x7fe0, 0x0010));
  pixels.SetVR(gdcm::VR::OW);
  pixels.SetByteValue(reinterpret_cast<const char *>(values.data()), static_cast<std::uint32_t>(4 * values.size()));
  ds.Replace(pixels);
  dicomrt::WriteDataSetAtomically(ds, path, Where);
}

} // namespace itk

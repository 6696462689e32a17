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
// DICOM-RT input, dose: RTDOSE -> dose image [Gy]; a dose image from an RTDOSE or another image format.
#include "itkDicomRT.h"

#include "bmrError.h"
#include "itkBiomechanicalImageIO.h"
#include "itkDicomRTCommon.h"

#include "gdcmDataSet.h"
#include "gdcmImage.h"
#include "gdcmImageReader.h"
#include "gdcmTag.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace itk {
namespace {
using dicomrt::CheckDicomFile;
using dicomrt::CheckModality;
using dicomrt::FailFile;
using dicomrt::ParseNumbers;
using dicomrt::Quote;
using dicomrt::ReadParsedFile;
using dicomrt::StringValue;
using dicomrt::Upper;

const gdcm::Tag ImagePositionPatientTag(0x0020, 0x0032);
const gdcm::Tag ImageOrientationPatientTag(0x0020, 0x0037);
const gdcm::Tag PixelSpacingTag(0x0028, 0x0030);
const gdcm::Tag DoseUnitsTag(0x3004, 0x0002);
const gdcm::Tag GridFrameOffsetVectorTag(0x3004, 0x000c);
const gdcm::Tag DoseGridScalingTag(0x3004, 0x000e);

constexpr const char * RTDoseWhere = "ReadRTDose";

/** The numbers of an attribute of the RTDOSE (dicomrt::FileNumbers()). */
std::vector<double>
RequireNumbers(const gdcm::DataSet & ds, const gdcm::Tag & tag, const std::string & name, const std::string & path)
{
  return dicomrt::FileNumbers(ds, tag, name, 0, RTDoseWhere, "RTDOSE", path);
}

/** The positions of the \a frames frames along the normal, relative to the Image Position \a position (the Grid
 * Frame Offset Vector, made relative when it holds z coordinates). */
std::vector<double>
FrameOffsets(const gdcm::DataSet &         ds,
             unsigned int                  frames,
             const std::vector<double> &   position,
             const std::array<double, 3> & row,
             const std::array<double, 3> & column,
             const std::string &           path)
{
  // Frame positions along the normal, relative to the Image Position.
  std::vector<double> offsets(1, 0.0);
  if (frames > 1 || ds.FindDataElement(GridFrameOffsetVectorTag))
  {
    offsets = RequireNumbers(ds, GridFrameOffsetVectorTag, "Grid Frame Offset Vector", path);
  }
  if (offsets.size() != frames)
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "its Grid Frame Offset Vector has " + std::to_string(offsets.size()) + " values for " +
               std::to_string(frames) + " frames");
  }
  if (offsets[0] != 0.0)
  {
    // DICOM PS3.3 C.8.8.3.2: a first value other than 0 makes the vector the frames' z coordinates, which is
    // allowed only for the axial orientation 1\0\0\0\1\0.
    const bool axial = std::abs(row[0] - 1) < 1e-6 && std::abs(column[1] - 1) < 1e-6;
    if (!axial)
    {
      FailFile(RTDoseWhere,
               "RTDOSE",
               path,
               "its Grid Frame Offset Vector starts at a non-zero value (z coordinates) on a non-axial grid");
    }
    for (auto & o : offsets)
    {
      o -= position[2];
    }
  }
  return offsets;
}

/** The even spacing of the frames at \a offsets [mm], signed (one frame: a nominal 1 mm); fails when they are not
 * evenly spaced. */
double
FrameStep(const std::vector<double> & offsets, unsigned int frames, const std::string & path)
{
  double step = 1.0; // one frame: a nominal slice spacing [mm]
  if (frames > 1)
  {
    step = (offsets.back() - offsets.front()) / static_cast<double>(frames - 1);
    double smallest = std::numeric_limits<double>::infinity(), largest = -smallest;
    for (unsigned int f = 1; f < frames; ++f)
    {
      smallest = std::min(smallest, offsets[f] - offsets[f - 1]);
      largest = std::max(largest, offsets[f] - offsets[f - 1]);
    }
    const double allowed = std::max(1e-3 * std::abs(step), 1e-3); // mm: DS text rounding
    if (step == 0.0 || largest - step > allowed || step - smallest > allowed)
    {
      std::ostringstream os;
      os << "its frames are not evenly spaced (Grid Frame Offset Vector steps from " << smallest << " to " << largest
         << " mm)";
      FailFile(RTDoseWhere, "RTDOSE", path, os.str());
    }
  }
  return step;
}

/** Origin [mm], spacing [mm] and direction of the dose grid from its position, orientation, pixel spacing and
 * frame offsets. */
void
SetDoseGeometry(const gdcm::DataSet & ds, unsigned int frames, DicomRTDoseImageType * image, const std::string & path)
{
  const auto position = RequireNumbers(ds, ImagePositionPatientTag, "Image Position (Patient)", path);
  const auto orientation = RequireNumbers(ds, ImageOrientationPatientTag, "Image Orientation (Patient)", path);
  const auto pixelSpacing = RequireNumbers(ds, PixelSpacingTag, "Pixel Spacing", path);
  if (position.size() != 3 || orientation.size() != 6 || pixelSpacing.size() != 2 || pixelSpacing[0] <= 0 ||
      pixelSpacing[1] <= 0)
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "its Image Position (3 values), Image Orientation (6) or Pixel Spacing (2 positive) is malformed");
  }
  std::array<double, 3> row, column, normal;
  if (!dicomrt::OrientationAxes(orientation, row, column, normal))
  {
    FailFile(RTDoseWhere, "RTDOSE", path, "its Image Orientation (Patient) is not two orthogonal unit vectors");
  }
  const std::vector<double>           offsets = FrameOffsets(ds, frames, position, row, column, path);
  const double                        step = FrameStep(offsets, frames, path);
  DicomRTDoseImageType::PointType     origin;
  DicomRTDoseImageType::SpacingType   spacing;
  DicomRTDoseImageType::DirectionType direction;
  const double                        sign = step < 0 ? -1.0 : 1.0;
  for (unsigned int a = 0; a < 3; ++a)
  {
    origin[a] = position[a] + offsets[0] * normal[a];
    direction(a, 0) = row[a];
    direction(a, 1) = column[a];
    direction(a, 2) = sign * normal[a];
  }
  spacing[0] = pixelSpacing[1]; // DICOM: spacing between rows, then between columns
  spacing[1] = pixelSpacing[0];
  spacing[2] = std::abs(step);
  image->SetOrigin(origin);
  image->SetSpacing(spacing);
  image->SetDirection(direction);
}

/** Stored value number \a i of a buffer of 16- or 32-bit, signed or unsigned, little-endian integers (GDCM
 * delivers the decoded buffer in the machine's byte order, little endian on every platform we build for). */
double
StoredValue(const std::vector<char> & buffer, std::size_t i, unsigned int bits, bool isSigned)
{
  if (bits == 16)
  {
    std::uint16_t v;
    std::memcpy(&v, buffer.data() + 2 * i, 2);
    return isSigned ? static_cast<double>(static_cast<std::int16_t>(v)) : static_cast<double>(v);
  }
  std::uint32_t v;
  std::memcpy(&v, buffer.data() + 4 * i, 4);
  return isSigned ? static_cast<double>(static_cast<std::int32_t>(v)) : static_cast<double>(v);
}

/** The Dose Grid Scaling [Gy per stored value] of an RTDOSE whose Dose Units are GY; fails otherwise. */
double
DoseGridScaling(const gdcm::DataSet & ds, const std::string & path)
{
  const std::string units = Upper(StringValue(ds, DoseUnitsTag));
  if (units != "GY")
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "its Dose Units (3004,0002) are " + (units.empty() ? std::string("missing") : Quote(units)) +
               ", not GY (a relative dose cannot be used as Gy)");
  }
  const auto scaling = RequireNumbers(ds, DoseGridScalingTag, "Dose Grid Scaling", path);
  if (scaling.size() != 1 || !(scaling[0] > 0))
  {
    FailFile(RTDoseWhere, "RTDOSE", path, "its Dose Grid Scaling (3004,000E) is not one positive number");
  }
  return scaling[0];
}

/** The decoded pixel data of an RTDOSE: columns x rows x frames stored values of \a bits bits, signed or not. */
struct DosePixels
{
  unsigned int      bits;
  unsigned int      columns;
  unsigned int      rows;
  unsigned int      frames;
  std::size_t       voxels;
  bool              isSigned;
  std::vector<char> buffer;
};

/** Decodes the pixel data of \a gdcmImage: one sample of 16 or 32 bits per pixel, a sensible grid, as many values as
 * it declares; fails otherwise. */
DosePixels
DecodeDosePixels(const gdcm::Image & gdcmImage, const std::string & path)
{
  const gdcm::PixelFormat & format = gdcmImage.GetPixelFormat();
  const unsigned int        bits = format.GetBitsAllocated();
  if (format.GetSamplesPerPixel() != 1 || (bits != 16 && bits != 32))
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "its pixels are " + std::to_string(format.GetSamplesPerPixel()) + " sample(s) of " + std::to_string(bits) +
               " bits; one sample of 16 or 32 bits is required");
  }
  const unsigned int columns = gdcmImage.GetDimension(0);
  const unsigned int rows = gdcmImage.GetDimension(1);
  const unsigned int frames = gdcmImage.GetNumberOfDimensions() > 2 ? gdcmImage.GetDimension(2) : 1;
  const double       declared = static_cast<double>(columns) * rows * frames;
  if (columns == 0 || rows == 0 || frames == 0 || declared > BiomechanicalMaximumNumberOfVoxels)
  {
    FailFile(RTDoseWhere, "RTDOSE", path, "declares an empty or absurd grid (Rows x Columns x Number of Frames)");
  }
  const std::size_t voxels = static_cast<std::size_t>(columns) * rows * frames;
  std::vector<char> buffer(std::max<std::size_t>(gdcmImage.GetBufferLength(), 1));
  bool              decoded = false;
  try
  {
    decoded = gdcmImage.GetBuffer(buffer.data());
  }
  catch (const std::exception &)
  {
    decoded = false;
  }
  if (!decoded || gdcmImage.GetBufferLength() < voxels * (bits / 8))
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "its pixel data hold fewer values than Rows x Columns x Number of Frames (truncated or corrupt)");
  }
  return { bits, columns, rows, frames, voxels, format.GetPixelRepresentation() == 1, std::move(buffer) };
}
} // namespace

DicomRTDoseImageType::Pointer
ReadRTDose(const std::string & path)
{
  CheckDicomFile(RTDoseWhere, "RTDOSE", path);
  const std::string modality = ReadDicomModality(path);
  if (modality != "RTDOSE")
  {
    FailFile(RTDoseWhere,
             "RTDOSE",
             path,
             "is not an RTDOSE (Modality " + (modality.empty() ? std::string("missing") : Quote(modality)) + ")");
  }
  gdcm::ImageReader reader;
  ReadParsedFile(reader, RTDoseWhere, "RTDOSE", path);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  CheckModality(ds, "RTDOSE", RTDoseWhere, path);
  const double     scaling = DoseGridScaling(ds, path);
  const DosePixels pixels = DecodeDosePixels(reader.GetImage(), path);

  auto                             dose = DicomRTDoseImageType::New();
  DicomRTDoseImageType::RegionType region;
  region.SetSize(0, pixels.columns);
  region.SetSize(1, pixels.rows);
  region.SetSize(2, pixels.frames);
  dose->SetRegions(region);
  SetDoseGeometry(ds, pixels.frames, dose.GetPointer(), path);
  dose->Allocate();
  float * values = dose->GetBufferPointer();
  for (std::size_t i = 0; i < pixels.voxels; ++i)
  {
    values[i] = static_cast<float>(StoredValue(pixels.buffer, i, pixels.bits, pixels.isSigned) * scaling);
  }
  return dose;
}

DicomRTDoseImageType::Pointer
ReadDoseImage(const std::string & path)
{
  if (ReadDicomModality(path) == "RTDOSE")
  {
    return ReadRTDose(path);
  }
  return ReadBiomechanicalImage<DicomRTDoseImageType>(path, "dose image");
}

} // namespace itk

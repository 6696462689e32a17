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
// DICOM-RT input: RTSTRUCT -> label map on a CT grid, RTDOSE -> dose image [Gy]. GDCM is used only in this
// unit; attributes are read from the raw element values (strings parsed here) rather than through
// gdcm::Attribute, whose conversions assume well-formed values, so that a corrupt file gives an error.
#include "itkDicomRT.h"

#include "bmrError.h"
#include "itkBiomechanicalImageIO.h"
#include "itkDicomRTCommon.h"
#include "itkPlanarContours.h"

#include "gdcmDataSet.h"
#include "gdcmImage.h"
#include "gdcmImageReader.h"
#include "gdcmItem.h"
#include "gdcmReader.h"
#include "gdcmSequenceOfItems.h"
#include "gdcmTag.h"
#include "gdcmTrace.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>

namespace itk {
namespace {
using dicomrt::HasPart10Preamble;
using dicomrt::NameKey;
using dicomrt::ParseNumbers;
using dicomrt::StringValue;
using dicomrt::Trim;
using dicomrt::Upper;

// ------------------------------------------------------------------------------------------ tags

const gdcm::Tag ModalityTag(0x0008, 0x0060);
const gdcm::Tag SeriesInstanceUIDTag(0x0020, 0x000e);
const gdcm::Tag ImagePositionPatientTag(0x0020, 0x0032);
const gdcm::Tag ImageOrientationPatientTag(0x0020, 0x0037);
const gdcm::Tag PixelSpacingTag(0x0028, 0x0030);
const gdcm::Tag DoseUnitsTag(0x3004, 0x0002);
const gdcm::Tag GridFrameOffsetVectorTag(0x3004, 0x000c);
const gdcm::Tag DoseGridScalingTag(0x3004, 0x000e);
const gdcm::Tag ReferencedFrameOfReferenceSequenceTag(0x3006, 0x0010);
const gdcm::Tag RTReferencedStudySequenceTag(0x3006, 0x0012);
const gdcm::Tag RTReferencedSeriesSequenceTag(0x3006, 0x0014);
const gdcm::Tag StructureSetROISequenceTag(0x3006, 0x0020);
const gdcm::Tag ROINumberTag(0x3006, 0x0022);
const gdcm::Tag ROINameTag(0x3006, 0x0026);
const gdcm::Tag ROIContourSequenceTag(0x3006, 0x0039);
const gdcm::Tag ContourSequenceTag(0x3006, 0x0040);
const gdcm::Tag ContourGeometricTypeTag(0x3006, 0x0042);
const gdcm::Tag NumberOfContourPointsTag(0x3006, 0x0046);
const gdcm::Tag ContourDataTag(0x3006, 0x0050);
const gdcm::Tag ReferencedROINumberTag(0x3006, 0x0084);

// ------------------------------------------------------------------------------------------ text

std::string
Quote(const std::string & text)
{
  return "\"" + text + "\"";
}

std::string
JoinQuoted(const std::vector<std::string> & names)
{
  std::string joined;
  for (const auto & n : names)
  {
    joined += (joined.empty() ? "" : ", ") + Quote(n);
  }
  return joined.empty() ? "none" : joined;
}

/** Throws naming the file: `<kind> "<path>": <message>`. */
[[noreturn]] void
FailFile(const char * where, const std::string & kind, const std::string & path, const std::string & message)
{
  bmr::Fail(where, kind + " " + Quote(path) + ": " + message);
}

// ------------------------------------------------------------------------------------------ DICOM values

/** The sequence at \a tag, or nullptr when it is absent, empty or cannot be decoded. */
gdcm::SmartPointer<gdcm::SequenceOfItems>
Sequence(const gdcm::DataSet & ds, const gdcm::Tag & tag)
{
  if (!ds.FindDataElement(tag))
  {
    return nullptr;
  }
  try
  {
    gdcm::SmartPointer<gdcm::SequenceOfItems> sq = ds.GetDataElement(tag).GetValueAsSQ();
    if (sq && sq->GetNumberOfItems() > 0)
    {
      return sq;
    }
  }
  catch (const std::exception &)
  {
    // An undecodable sequence is reported by the caller as missing.
  }
  return nullptr;
}

/** Turns GDCM's diagnostics (printed on std::cerr by Debian's build) off while it lives. */
class QuietGDCM
{
public:
  QuietGDCM()
    : m_Warning(gdcm::Trace::GetWarningFlag())
    , m_Error(gdcm::Trace::GetErrorFlag())
  {
    gdcm::Trace::WarningOff();
    gdcm::Trace::ErrorOff();
  }
  ~QuietGDCM()
  {
    gdcm::Trace::SetWarning(m_Warning);
    gdcm::Trace::SetError(m_Error);
  }
  QuietGDCM(const QuietGDCM &) = delete;
  QuietGDCM &
  operator=(const QuietGDCM &) = delete;

private:
  bool m_Warning;
  bool m_Error;
};

/** Refuses, naming the file, what GDCM must not see: not a file, not DICOM Part 10, or an incomplete structure. */
void
CheckDicomFile(const char * where, const std::string & kind, const std::string & path)
{
  std::ifstream file(path, std::ios::binary);
  if (!file || std::filesystem::is_directory(path))
  {
    FailFile(where, kind, path, "cannot be opened");
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.size() < 132 || std::memcmp(bytes.data() + 128, "DICM", 4) != 0)
  {
    FailFile(where, kind, path, "is not a DICOM file");
  }
  const std::string problem = dicomrt::DicomStructureProblem(std::move(bytes));
  if (!problem.empty())
  {
    FailFile(where, kind, path, "is corrupt: " + problem);
  }
}

/** Parses \a path with \a reader (a gdcm::Reader or gdcm::ImageReader) after CheckDicomFile(); throws naming the
 * file when GDCM cannot. */
void
ReadParsedFile(gdcm::Reader & reader, const char * where, const std::string & kind, const std::string & path)
{
  QuietGDCM quiet;
  bool      ok = false;
  reader.SetFileName(path.c_str());
  try
  {
    ok = reader.Read();
  }
  catch (const std::exception &)
  {
    ok = false;
  }
  if (!ok)
  {
    FailFile(where, kind, path, "cannot be read as DICOM (corrupt)");
  }
}

void
CheckModality(const gdcm::DataSet & ds, const std::string & expected, const char * where, const std::string & path)
{
  const std::string modality = Upper(StringValue(ds, ModalityTag));
  if (modality != expected)
  {
    FailFile(where,
             expected,
             path,
             "is not an " + expected + " (Modality " + (modality.empty() ? "missing" : Quote(modality)) + ")");
  }
}

// ------------------------------------------------------------------------------------------ RTSTRUCT

constexpr const char * RTStructWhere = "ReadRTStructAsLabelImage";

struct ROI
{
  std::string          name;
  long                 number{ 0 };
  std::vector<PlanarContour> contours;
  bool                 mapped{ false };
  std::int32_t         label{ 0 };
};

/** Requires a Referenced Frame of Reference Sequence naming at least one referenced series: the structures
 * must say which images they were drawn on. */
void
CheckReferencedSeries(const gdcm::DataSet & ds, const std::string & path)
{
  const auto frames = Sequence(ds, ReferencedFrameOfReferenceSequenceTag);
  if (!frames)
  {
    FailFile(RTStructWhere, "RTSTRUCT", path, "has no Referenced Frame of Reference Sequence (3006,0010)");
  }
  for (gdcm::SequenceOfItems::SizeType f = 1; f <= frames->GetNumberOfItems(); ++f)
  {
    const auto studies = Sequence(frames->GetItem(f).GetNestedDataSet(), RTReferencedStudySequenceTag);
    for (gdcm::SequenceOfItems::SizeType s = 1; studies && s <= studies->GetNumberOfItems(); ++s)
    {
      const auto series = Sequence(studies->GetItem(s).GetNestedDataSet(), RTReferencedSeriesSequenceTag);
      for (gdcm::SequenceOfItems::SizeType r = 1; series && r <= series->GetNumberOfItems(); ++r)
      {
        if (!StringValue(series->GetItem(r).GetNestedDataSet(), SeriesInstanceUIDTag).empty())
        {
          return;
        }
      }
    }
  }
  FailFile(RTStructWhere,
           "RTSTRUCT",
           path,
           "references no image series (no Series Instance UID in the Referenced Frame of Reference Sequence)");
}

long
ParseROINumber(const std::string & text, const std::string & path, const std::string & context)
{
  std::vector<double> values;
  if (!ParseNumbers(text, values) || values.size() != 1 || values[0] != std::floor(values[0]) ||
      std::abs(values[0]) > 2147483647.0)
  {
    FailFile(RTStructWhere, "RTSTRUCT", path, context + " has no valid ROI number (" + Quote(text) + ")");
  }
  return static_cast<long>(values[0]);
}

/** The ROIs of the Structure Set ROI Sequence (number and name), in file order. */
std::vector<ROI>
ReadROIs(const gdcm::DataSet & ds, const std::string & path)
{
  const auto sq = Sequence(ds, StructureSetROISequenceTag);
  if (!sq)
  {
    FailFile(RTStructWhere, "RTSTRUCT", path, "has no Structure Set ROI Sequence (3006,0020)");
  }
  std::vector<ROI> rois;
  for (gdcm::SequenceOfItems::SizeType i = 1; i <= sq->GetNumberOfItems(); ++i)
  {
    const gdcm::DataSet & item = sq->GetItem(i).GetNestedDataSet();
    ROI                   roi;
    roi.name = StringValue(item, ROINameTag);
    roi.number = ParseROINumber(
      StringValue(item, ROINumberTag), path, "ROI " + Quote(roi.name) + " (item " + std::to_string(i) + ")");
    rois.push_back(roi);
  }
  return rois;
}

/** Marks the ROIs named in \a roiNameToLabel and gives them their label; every ROI must be mapped unless
 * \a ignoreUnmapped, every map entry must name one ROI. */
void
MapROIs(std::vector<ROI> &                          rois,
        const std::map<std::string, std::int32_t> & roiNameToLabel,
        bool                                        ignoreUnmapped,
        const std::string &                         path)
{
  std::map<std::string, std::pair<std::string, std::int32_t>> byKey; // key -> (name as given, label)
  std::vector<std::string>                                    mapNames;
  for (const auto & kv : roiNameToLabel)
  {
    if (!byKey.emplace(NameKey(kv.first), kv).second)
    {
      FailFile(RTStructWhere,
               "RTSTRUCT",
               path,
               "the ROI names " + Quote(byKey.at(NameKey(kv.first)).first) + " and " + Quote(kv.first) +
                 " of the label map are the same name");
    }
    mapNames.push_back(kv.first);
  }
  std::map<std::string, const ROI *> found;
  for (auto & roi : rois)
  {
    const auto entry = byKey.find(NameKey(roi.name));
    if (entry == byKey.end())
    {
      if (!ignoreUnmapped)
      {
        FailFile(RTStructWhere,
                 "RTSTRUCT",
                 path,
                 "ROI " + Quote(roi.name) + " is not one of the known names (" + JoinQuoted(mapNames) + ")");
      }
      continue;
    }
    if (!found.emplace(entry->first, &roi).second)
    {
      FailFile(RTStructWhere, "RTSTRUCT", path, "two ROIs are named " + Quote(roi.name));
    }
    roi.mapped = true;
    roi.label = entry->second.second;
  }
  std::vector<std::string> fileNames;
  for (const auto & roi : rois)
  {
    fileNames.push_back(roi.name);
  }
  for (const auto & kv : byKey)
  {
    if (!found.count(kv.first))
    {
      FailFile(RTStructWhere,
               "RTSTRUCT",
               path,
               "has no ROI named " + Quote(kv.second.first) + " (its ROIs: " + JoinQuoted(fileNames) + ")");
    }
  }
}

PlanarContour
ReadContour(const gdcm::DataSet & item, const ROI & roi, std::size_t index, const std::string & path)
{
  const std::string what = "ROI " + Quote(roi.name) + ", contour " + std::to_string(index);
  const std::string type = Upper(StringValue(item, ContourGeometricTypeTag));
  if (type != "CLOSED_PLANAR")
  {
    FailFile(RTStructWhere,
             "RTSTRUCT",
             path,
             what + " is " + (type.empty() ? "of no geometric type" : type) +
               "; only CLOSED_PLANAR contours are rasterized");
  }
  std::vector<double> count;
  std::vector<double> coordinates;
  if (!ParseNumbers(StringValue(item, NumberOfContourPointsTag), count) || count.size() != 1)
  {
    FailFile(RTStructWhere, "RTSTRUCT", path, what + " has no valid Number of Contour Points (3006,0046)");
  }
  if (!ParseNumbers(StringValue(item, ContourDataTag), coordinates))
  {
    FailFile(RTStructWhere, "RTSTRUCT", path, what + ": its Contour Data (3006,0050) hold a value that is no number");
  }
  if (count[0] < 3 || count[0] > 1e8 || coordinates.size() != 3 * static_cast<std::size_t>(count[0]))
  {
    std::ostringstream os;
    os << what << " has " << coordinates.size() << " coordinates for " << count[0]
       << " points (3 per point, at least 3 points)";
    FailFile(RTStructWhere, "RTSTRUCT", path, os.str());
  }
  PlanarContour contour;
  for (std::size_t p = 0; p < coordinates.size(); p += 3)
  {
    ImageBase<3>::PointType point;
    point[0] = coordinates[p];
    point[1] = coordinates[p + 1];
    point[2] = coordinates[p + 2];
    contour.points.push_back(point);
  }
  return contour;
}

/** Reads the contours of the mapped ROIs from the ROI Contour Sequence. */
void
ReadContours(const gdcm::DataSet & ds, std::vector<ROI> & rois, const std::string & path)
{
  const auto sq = Sequence(ds, ROIContourSequenceTag);
  for (gdcm::SequenceOfItems::SizeType i = 1; sq && i <= sq->GetNumberOfItems(); ++i)
  {
    const gdcm::DataSet & item = sq->GetItem(i).GetNestedDataSet();
    const long            number =
      ParseROINumber(StringValue(item, ReferencedROINumberTag), path, "ROI Contour Sequence item " + std::to_string(i));
    const auto roi = std::find_if(rois.begin(), rois.end(), [number](const ROI & r) { return r.number == number; });
    if (roi == rois.end())
    {
      FailFile(RTStructWhere,
               "RTSTRUCT",
               path,
               "ROI Contour Sequence item " + std::to_string(i) + " refers to ROI number " + std::to_string(number) +
                 ", which the Structure Set ROI Sequence does not define");
    }
    if (!roi->mapped)
    {
      continue;
    }
    const auto contours = Sequence(item, ContourSequenceTag);
    for (gdcm::SequenceOfItems::SizeType c = 1; contours && c <= contours->GetNumberOfItems(); ++c)
    {
      roi->contours.push_back(ReadContour(contours->GetItem(c).GetNestedDataSet(), *roi, c, path));
    }
  }
  for (const auto & roi : rois)
  {
    if (roi.mapped && roi.contours.empty())
    {
      FailFile(RTStructWhere, "RTSTRUCT", path, "ROI " + Quote(roi.name) + " has no contour");
    }
  }
}

/** A run of voxels of one row, as offsets into the output buffer. */
struct Run
{
  std::size_t start;
  std::size_t length;
};

/** Even-odd fill of one slice: along each row j (y = j), voxel centre i is inside when an odd number of edges
 * cross the row left of it (detail::RowCrossings()). */
void
FillSlice(const std::vector<detail::ContourEdge> & edges, long slice, const ImageRegion<3> & region, std::vector<Run> & runs)
{
  const long          nx = static_cast<long>(region.GetSize(0));
  const long          ny = static_cast<long>(region.GetSize(1));
  std::vector<double> crossings;
  for (long j = 0; j < ny; ++j)
  {
    detail::RowCrossings(edges, static_cast<double>(j), crossings);
    for (std::size_t m = 0; m + 1 < crossings.size(); m += 2)
    {
      // Centres i with crossings[m] < i <= crossings[m + 1] have an odd count of crossings left of them.
      const long first = std::max(0L, static_cast<long>(std::floor(crossings[m])) + 1);
      const long last = std::min(nx - 1, static_cast<long>(std::floor(crossings[m + 1])));
      if (first <= last)
      {
        const std::size_t row = static_cast<std::size_t>(nx) * static_cast<std::size_t>(j + ny * slice);
        runs.push_back({ row + static_cast<std::size_t>(first), static_cast<std::size_t>(last - first + 1) });
      }
    }
  }
}

/** The owner of \a roi's contours in messages: RTSTRUCT "path": ROI "name". */
std::string
ContourOwner(const ROI & roi, const std::string & path)
{
  return "RTSTRUCT " + Quote(path) + ": ROI " + Quote(roi.name);
}

std::vector<Run>
RasterizeROI(const ROI & roi, const ImageBase<3> * grid, const std::string & path)
{
  std::vector<Run> runs;
  for (const auto & slice : detail::ContourEdgesPerSlice(roi.contours, grid, RTStructWhere, ContourOwner(roi, path)))
  {
    FillSlice(slice.second, slice.first, grid->GetLargestPossibleRegion(), runs);
  }
  return runs;
}

DicomRTLabelImageType::Pointer
MakeLabelImage(const ImageBase<3> * grid, std::int32_t background)
{
  // The grid's geometry, 0-based (the origin at its region's start); filled in place rather than copied from a
  // vector of the image's size.
  auto labels = MakeImageOnGrid<DicomRTLabelImageType>(GridGeometryOf(grid), {});
  labels->FillBuffer(background);
  return labels;
}

// ------------------------------------------------------------------------------------------ RTDOSE

constexpr const char * RTDoseWhere = "ReadRTDose";

std::vector<double>
RequireNumbers(const gdcm::DataSet & ds, const gdcm::Tag & tag, const std::string & name, const std::string & path)
{
  std::vector<double> values;
  if (!ds.FindDataElement(tag) || !ParseNumbers(StringValue(ds, tag), values) || values.empty())
  {
    std::ostringstream os;
    os << "has no valid " << name << " " << tag;
    FailFile(RTDoseWhere, "RTDOSE", path, os.str());
  }
  return values;
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
  const std::array<double, 3> row{ { orientation[0], orientation[1], orientation[2] } };
  const std::array<double, 3> column{ { orientation[3], orientation[4], orientation[5] } };
  const std::array<double, 3> normal{ { row[1] * column[2] - row[2] * column[1],
                                        row[2] * column[0] - row[0] * column[2],
                                        row[0] * column[1] - row[1] * column[0] } };
  const double                rowLength = std::sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2]);
  const double columnLength = std::sqrt(column[0] * column[0] + column[1] * column[1] + column[2] * column[2]);
  const double dot = row[0] * column[0] + row[1] * column[1] + row[2] * column[2];
  if (std::abs(rowLength - 1) > 1e-3 || std::abs(columnLength - 1) > 1e-3 || std::abs(dot) > 1e-3)
  {
    FailFile(RTDoseWhere, "RTDOSE", path, "its Image Orientation (Patient) is not two orthogonal unit vectors");
  }

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

} // namespace

// ------------------------------------------------------------------------------------------ public

std::string
ReadDicomModality(const std::string & path)
{
  try
  {
    if (std::filesystem::is_directory(path) || !HasPart10Preamble(path))
    {
      return std::string();
    }
    // The Modality comes early in the file (group 0008): a prefix is enough, whatever the file's size.
    constexpr std::size_t      prefixBytes = 1 << 20;
    std::ifstream              file(path, std::ios::binary);
    std::vector<unsigned char> bytes(prefixBytes);
    file.read(reinterpret_cast<char *>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<std::size_t>(file.gcount()));
    return dicomrt::DicomModalityOfPrefix(std::move(bytes));
  }
  catch (const std::exception &)
  {
    return std::string();
  }
}

std::vector<std::string>
ReadRTStructROINames(const std::string & rtstructPath)
{
  gdcm::Reader reader;
  CheckDicomFile("ReadRTStructROINames", "RTSTRUCT", rtstructPath);
  ReadParsedFile(reader, "ReadRTStructROINames", "RTSTRUCT", rtstructPath);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  CheckModality(ds, "RTSTRUCT", "ReadRTStructROINames", rtstructPath);
  std::vector<std::string> names;
  for (const auto & roi : ReadROIs(ds, rtstructPath))
  {
    names.push_back(roi.name);
  }
  return names;
}

DicomRTLabelImageType::Pointer
ReadRTStructAsLabelImage(const std::string &                         rtstructPath,
                         const ImageBase<3> *                        referenceGrid,
                         const std::map<std::string, std::int32_t> & roiNameToLabel,
                         const RTStructRasterizationOptions &        options)
{
  if (!referenceGrid)
  {
    FailFile(RTStructWhere, "RTSTRUCT", rtstructPath, "no reference grid given");
  }
  gdcm::Reader reader;
  CheckDicomFile(RTStructWhere, "RTSTRUCT", rtstructPath);
  ReadParsedFile(reader, RTStructWhere, "RTSTRUCT", rtstructPath);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  CheckModality(ds, "RTSTRUCT", RTStructWhere, rtstructPath);
  CheckReferencedSeries(ds, rtstructPath);
  std::vector<ROI> rois = ReadROIs(ds, rtstructPath);
  MapROIs(rois, roiNameToLabel, options.ignoreUnmappedROIs, rtstructPath);
  ReadContours(ds, rois, rtstructPath);

  // Rasterize every mapped ROI, then paint the largest first: the ROI with the fewest voxels wins an overlap,
  // and among equal counts the first in the file (painted last).
  struct Painted
  {
    std::size_t      order;
    std::size_t      voxels;
    std::int32_t     label;
    std::vector<Run> runs;
  };
  std::vector<Painted> painted;
  for (std::size_t r = 0; r < rois.size(); ++r)
  {
    if (!rois[r].mapped)
    {
      continue;
    }
    Painted p{ r, 0, rois[r].label, RasterizeROI(rois[r], referenceGrid, rtstructPath) };
    for (const auto & run : p.runs)
    {
      p.voxels += run.length;
    }
    painted.push_back(std::move(p));
  }
  std::sort(painted.begin(), painted.end(), [](const Painted & a, const Painted & b) {
    return a.voxels != b.voxels ? a.voxels > b.voxels : a.order > b.order;
  });
  auto           labels = MakeLabelImage(referenceGrid, options.backgroundLabel);
  std::int32_t * buffer = labels->GetBufferPointer();
  for (const auto & p : painted)
  {
    for (const auto & run : p.runs)
    {
      std::fill(buffer + run.start, buffer + run.start + run.length, p.label);
    }
  }
  return labels;
}

std::map<std::string, ContourFractionImageType::Pointer>
ReadRTStructAreaFractions(const std::string &              rtstructPath,
                          const ImageBase<3> *             referenceGrid,
                          const std::vector<std::string> & roiNames)
{
  if (!referenceGrid)
  {
    FailFile(RTStructWhere, "RTSTRUCT", rtstructPath, "no reference grid given");
  }
  gdcm::Reader reader;
  CheckDicomFile(RTStructWhere, "RTSTRUCT", rtstructPath);
  ReadParsedFile(reader, RTStructWhere, "RTSTRUCT", rtstructPath);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  CheckModality(ds, "RTSTRUCT", RTStructWhere, rtstructPath);
  CheckReferencedSeries(ds, rtstructPath);
  std::vector<ROI>                    rois = ReadROIs(ds, rtstructPath);
  std::map<std::string, std::int32_t> wanted;
  for (const auto & name : roiNames)
  {
    wanted.emplace(name, 1);
  }
  MapROIs(rois, wanted, true, rtstructPath);
  ReadContours(ds, rois, rtstructPath);
  std::map<std::string, ContourFractionImageType::Pointer> fractions;
  for (const auto & roi : rois)
  {
    if (roi.mapped)
    {
      const auto name = std::find_if(roiNames.begin(), roiNames.end(), [&roi](const std::string & n) {
        return NameKey(n) == NameKey(roi.name);
      });
      fractions[*name] = PlanarContourAreaFractions(roi.contours, referenceGrid, ContourOwner(roi, rtstructPath));
    }
  }
  return fractions;
}

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

  const gdcm::Image &       gdcmImage = reader.GetImage();
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

  auto                             dose = DicomRTDoseImageType::New();
  DicomRTDoseImageType::RegionType region;
  region.SetSize(0, columns);
  region.SetSize(1, rows);
  region.SetSize(2, frames);
  dose->SetRegions(region);
  SetDoseGeometry(ds, frames, dose.GetPointer(), path);
  dose->Allocate();
  float *    values = dose->GetBufferPointer();
  const bool isSigned = format.GetPixelRepresentation() == 1;
  for (std::size_t i = 0; i < voxels; ++i)
  {
    values[i] = static_cast<float>(StoredValue(buffer, i, bits, isSigned) * scaling[0]);
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

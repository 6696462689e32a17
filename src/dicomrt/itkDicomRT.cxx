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
// DICOM-RT input, structures: RTSTRUCT -> label map or area fractions on a CT grid; the Modality of a file.
// Attributes are read from the raw element values (strings parsed here) rather than through gdcm::Attribute, whose
// conversions assume well-formed values, so that a corrupt file gives an error.
#include "itkDicomRT.h"

#include "bmrError.h"
#include "itkBiomechanicalImageIO.h"
#include "itkDicomRTCommon.h"
#include "itkPlanarContours.h"

#include "gdcmDataSet.h"
#include "gdcmItem.h"
#include "gdcmReader.h"
#include "gdcmSequenceOfItems.h"
#include "gdcmTag.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace itk {
namespace {
using dicomrt::CheckDicomFile;
using dicomrt::CheckModality;
using dicomrt::FailFile;
using dicomrt::HasPart10Preamble;
using dicomrt::NameKey;
using dicomrt::ParseNumbers;
using dicomrt::Quote;
using dicomrt::ReadParsedFile;
using dicomrt::Sequence;
using dicomrt::StringValue;
using dicomrt::Upper;

// ------------------------------------------------------------------------------------------ tags

const gdcm::Tag SeriesInstanceUIDTag(0x0020, 0x000e);
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
JoinQuoted(const std::vector<std::string> & names)
{
  std::string joined;
  for (const auto & n : names)
  {
    joined += (joined.empty() ? "" : ", ") + Quote(n);
  }
  return joined.empty() ? "none" : joined;
}

// ------------------------------------------------------------------------------------------ DICOM values


// ------------------------------------------------------------------------------------------ RTSTRUCT

constexpr const char * RTStructWhere = "ReadRTStructAsLabelImage";

struct ROI
{
  std::string                name;
  long                       number{ 0 };
  std::vector<PlanarContour> contours;
  bool                       mapped{ false };
  std::int32_t               label{ 0 };
};

/** Parses \a path into \a reader after the file checks, refuses another modality than RTSTRUCT; its data set. */
const gdcm::DataSet &
ReadRTStructFile(gdcm::Reader & reader, const char * where, const std::string & path)
{
  CheckDicomFile(where, "RTSTRUCT", path);
  ReadParsedFile(reader, where, "RTSTRUCT", path);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  CheckModality(ds, "RTSTRUCT", where, path);
  return ds;
}

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
FillSlice(const std::vector<detail::ContourEdge> & edges,
          long                                     slice,
          const ImageRegion<3> &                   region,
          std::vector<Run> &                       runs)
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
  gdcm::Reader             reader;
  const gdcm::DataSet &    ds = ReadRTStructFile(reader, "ReadRTStructROINames", rtstructPath);
  std::vector<std::string> names;
  for (const auto & roi : ReadROIs(ds, rtstructPath))
  {
    names.push_back(roi.name);
  }
  return names;
}

std::vector<std::string>
ReadRTStructFrameOfReferenceUIDs(const std::string & rtstructPath)
{
  gdcm::Reader             reader;
  const gdcm::DataSet &    ds = ReadRTStructFile(reader, "ReadRTStructFrameOfReferenceUIDs", rtstructPath);
  std::vector<std::string> uids;
  const auto               frames = Sequence(ds, ReferencedFrameOfReferenceSequenceTag);
  for (gdcm::SequenceOfItems::SizeType f = 1; frames && f <= frames->GetNumberOfItems(); ++f)
  {
    const std::string uid = StringValue(frames->GetItem(f).GetNestedDataSet(), gdcm::Tag(0x0020, 0x0052));
    if (!uid.empty())
    {
      uids.push_back(uid);
    }
  }
  return uids;
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
  gdcm::Reader          reader;
  const gdcm::DataSet & ds = ReadRTStructFile(reader, RTStructWhere, rtstructPath);
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
  gdcm::Reader          reader;
  const gdcm::DataSet & ds = ReadRTStructFile(reader, RTStructWhere, rtstructPath);
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
      const auto name = std::find_if(
        roiNames.begin(), roiNames.end(), [&roi](const std::string & n) { return NameKey(n) == NameKey(roi.name); });
      fractions[*name] = PlanarContourAreaFractions(roi.contours, referenceGrid, ContourOwner(roi, rtstructPath));
    }
  }
  return fractions;
}

} // namespace itk

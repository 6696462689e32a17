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
// WriteRTStruct: a label map's organs as the closed planar contours of a DICOM RT Structure Set.
#include "itkDicomRTWriters.h"
#include "itkPlanarContourFractions.h"

#include "bmrError.h"
#include "itkDicomRTCommon.h"

#include <cmath>
#include <set>
#include <sstream>

namespace itk {
namespace {
constexpr const char * Where = "WriteRTStruct";
constexpr const char * RTStructStorage = "1.2.840.10008.5.1.4.1.1.481.3";
constexpr const char * StudyComponentManagement = "1.2.840.10008.3.1.2.3.1"; // what a study is referenced as

using Vertex = std::array<double, 2>; // continuous index (i, j) in a slice

/** One closed planar contour: its slice and its points [LPS mm], 3 per vertex. */
struct Contour
{
  std::size_t         image; ///< index in the referenced series
  std::vector<double> points;
};

/** \a ring without its closing duplicate and without vertices on the line through their neighbours (the
 * marching squares put one on every voxel edge; they are exact half-integers, so the test is exact). */
std::vector<Vertex>
Simplified(std::vector<Vertex> ring)
{
  if (ring.size() > 1 && ring.front() == ring.back())
  {
    ring.pop_back();
  }
  std::vector<Vertex> kept;
  for (std::size_t i = 0; i < ring.size(); ++i)
  {
    const Vertex & a = kept.empty() ? ring.back() : kept.back();
    const Vertex & b = ring[i];
    const Vertex & c = ring[(i + 1) % ring.size()];
    if ((b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) != 0.0)
    {
      kept.push_back(b);
    }
  }
  return kept;
}

/** The contours of \a value's voxels on slice \a k, in patient coordinates. */
std::vector<std::vector<double>>
SliceContours(const DicomRTLabelImageType * labels, std::int32_t value, IndexValueType k)
{
  std::vector<std::vector<double>> contours;
  for (std::vector<Vertex> ring : LabelOutlinesOnSlice(labels, value, k))
  {
    ring = Simplified(ring);
    if (ring.size() < 3)
    {
      continue;
    }
    std::vector<double> points;
    for (const Vertex & v : ring)
    {
      ContinuousIndex<double, 3> index;
      index[0] = v[0];
      index[1] = v[1];
      index[2] = static_cast<double>(k);
      Point<double, 3> p;
      labels->TransformContinuousIndexToPhysicalPoint(index, p);
      points.insert(points.end(), { p[0], p[1], p[2] });
    }
    contours.push_back(points);
  }
  return contours;
}

std::array<double, 3>
Cross(const double * a, const double * b)
{
  return { { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] } };
}

/** For every slice of \a labels, the image of \a series at its position; fails when the grids differ. */
std::vector<std::size_t>
SliceImages(const DicomRTLabelImageType * labels, const dicomrt::ReferencedSeries & series)
{
  const auto & D = labels->GetDirection();
  for (unsigned int r = 0; r < 3; ++r)
  {
    if (std::abs(D(r, 0) - series.orientation[r]) > 1e-4 || std::abs(D(r, 1) - series.orientation[3 + r]) > 1e-4)
    {
      bmr::Fail(Where,
                "the label map's rows and columns are not oriented as the images of the reference series \"" +
                  series.directory + "\" (Image Orientation (Patient)): contours must lie in its slices");
    }
  }
  const std::array<double, 3> normal = Cross(&series.orientation[0], &series.orientation[3]);
  const auto   along = [&normal](const double * x) { return normal[0] * x[0] + normal[1] * x[1] + normal[2] * x[2]; };
  const auto & region = labels->GetLargestPossibleRegion();
  std::vector<std::size_t> images;
  for (IndexValueType k = region.GetIndex(2); k < region.GetIndex(2) + IndexValueType(region.GetSize(2)); ++k)
  {
    Point<double, 3> p;
    labels->TransformIndexToPhysicalPoint({ { region.GetIndex(0), region.GetIndex(1), k } }, p);
    std::size_t best = 0;
    for (std::size_t i = 1; i < series.images.size(); ++i)
    {
      if (std::abs(along(series.images[i].position.data()) - along(p.GetDataPointer())) <
          std::abs(along(series.images[best].position.data()) - along(p.GetDataPointer())))
      {
        best = i;
      }
    }
    if (std::abs(along(series.images[best].position.data()) - along(p.GetDataPointer())) > 0.01)
    {
      std::ostringstream os;
      os << "slice " << k << " of the label map (at " << along(p.GetDataPointer())
         << " mm along the normal) is no slice of the reference series \"" << series.directory
         << "\": the labels must lie on that series' grid";
      bmr::Fail(Where, os.str());
    }
    images.push_back(best);
  }
  return images;
}

void
CheckNames(const std::map<std::int32_t, std::string> & roiNames)
{
  std::set<std::string> seen;
  for (const auto & entry : roiNames)
  {
    const std::string name = dicomrt::Trim(entry.second);
    if (name.empty() || name.size() > 64 || name.find('\\') != std::string::npos)
    {
      bmr::Fail(Where,
                "the ROI name of label " + std::to_string(entry.first) + " (\"" + entry.second +
                  "\") must have 1 to 64 characters and no backslash");
    }
    // Names are matched without regard to case when read (ReadRTStructAsLabelImage).
    if (!seen.insert(dicomrt::NameKey(name)).second)
    {
      bmr::Fail(Where, "the ROI name \"" + name + "\" is given to two labels");
    }
  }
}

gdcm::DataSet
ImageReference(const dicomrt::ReferencedImage & image)
{
  gdcm::DataSet ds;
  dicomrt::Put(ds, gdcm::Tag(0x0008, 0x1150), gdcm::VR::UI, image.sopClassUID);
  dicomrt::Put(ds, gdcm::Tag(0x0008, 0x1155), gdcm::VR::UI, image.sopInstanceUID);
  return ds;
}

/** The Referenced Frame of Reference Sequence: the frame, the study, the series and every image of it. */
gdcm::DataSet
FrameReference(const dicomrt::ReferencedSeries & series)
{
  std::vector<gdcm::DataSet> images;
  for (const dicomrt::ReferencedImage & image : series.images)
  {
    images.push_back(ImageReference(image));
  }
  gdcm::DataSet seriesItem;
  dicomrt::Put(seriesItem, gdcm::Tag(0x0020, 0x000e), gdcm::VR::UI, series.seriesInstanceUID);
  dicomrt::PutSequence(seriesItem, gdcm::Tag(0x3006, 0x0016), images);
  gdcm::DataSet studyItem;
  dicomrt::Put(studyItem, gdcm::Tag(0x0008, 0x1150), gdcm::VR::UI, StudyComponentManagement);
  dicomrt::Put(studyItem,
               gdcm::Tag(0x0008, 0x1155),
               gdcm::VR::UI,
               dicomrt::StringValue(series.patientAndStudy, gdcm::Tag(0x0020, 0x000d)));
  dicomrt::PutSequence(studyItem, gdcm::Tag(0x3006, 0x0014), { seriesItem });
  gdcm::DataSet frame;
  dicomrt::Put(frame, gdcm::Tag(0x0020, 0x0052), gdcm::VR::UI, series.frameOfReferenceUID);
  dicomrt::PutSequence(frame, gdcm::Tag(0x3006, 0x0012), { studyItem });
  return frame;
}

/** One ROI's item of the ROI Contour Sequence; \a text collects its contour data (for the derived UIDs). */
gdcm::DataSet
RoiContourItem(int                               number,
               const std::vector<Contour> &      contours,
               const dicomrt::ReferencedSeries & series,
               std::string &                     text)
{
  static const int           palette[6][3] = { { 255, 0, 0 }, { 0, 160, 255 }, { 255, 200, 0 },
                                               { 0, 200, 0 }, { 200, 0, 255 }, { 255, 128, 128 } };
  std::vector<gdcm::DataSet> items;
  for (const Contour & contour : contours)
  {
    gdcm::DataSet item;
    dicomrt::PutSequence(item, gdcm::Tag(0x3006, 0x0016), { ImageReference(series.images[contour.image]) });
    dicomrt::Put(item, gdcm::Tag(0x3006, 0x0042), gdcm::VR::CS, "CLOSED_PLANAR");
    dicomrt::Put(item, gdcm::Tag(0x3006, 0x0046), gdcm::VR::IS, std::to_string(contour.points.size() / 3));
    dicomrt::Put(item, gdcm::Tag(0x3006, 0x0048), gdcm::VR::IS, std::to_string(items.size() + 1));
    const std::string data = dicomrt::DecimalStrings(contour.points.data(), contour.points.size());
    dicomrt::Put(item, gdcm::Tag(0x3006, 0x0050), gdcm::VR::DS, data);
    text += data;
    items.push_back(item);
  }
  const int *   color = palette[(number - 1) % 6];
  gdcm::DataSet roi;
  dicomrt::Put(roi,
               gdcm::Tag(0x3006, 0x002a),
               gdcm::VR::IS,
               std::to_string(color[0]) + "\\" + std::to_string(color[1]) + "\\" + std::to_string(color[2]));
  dicomrt::PutSequence(roi, gdcm::Tag(0x3006, 0x0040), items);
  dicomrt::Put(roi, gdcm::Tag(0x3006, 0x0084), gdcm::VR::IS, std::to_string(number));
  return roi;
}
} // namespace

void
WriteRTStruct(const DicomRTLabelImageType *               labels,
              const std::map<std::int32_t, std::string> & roiNames,
              const std::string &                         referenceSeries,
              const std::string &                         path)
{
  if (labels == nullptr)
  {
    bmr::Fail(Where, "no label map");
  }
  CheckNames(roiNames);
  const dicomrt::ReferencedSeries series = dicomrt::ReadReferencedSeries(referenceSeries, Where);
  const std::vector<std::size_t>  sliceImages = SliceImages(labels, series);
  const IndexValueType            k0 = labels->GetLargestPossibleRegion().GetIndex(2);

  std::vector<gdcm::DataSet> rois, contourItems, observations;
  std::string                text; // names and contour data: what the derived UIDs are derived from
  for (const auto & entry : roiNames)
  {
    std::vector<Contour> contours;
    for (std::size_t s = 0; s < sliceImages.size(); ++s)
    {
      for (auto & points : SliceContours(labels, entry.first, k0 + IndexValueType(s)))
      {
        contours.push_back({ sliceImages[s], std::move(points) });
      }
    }
    if (contours.empty())
    {
      continue; // the label holds no voxel: no ROI
    }
    const int         number = static_cast<int>(rois.size() + 1);
    const std::string name = dicomrt::Trim(entry.second);
    gdcm::DataSet     roi;
    dicomrt::Put(roi, gdcm::Tag(0x3006, 0x0022), gdcm::VR::IS, std::to_string(number));
    dicomrt::Put(roi, gdcm::Tag(0x3006, 0x0024), gdcm::VR::UI, series.frameOfReferenceUID);
    dicomrt::Put(roi, gdcm::Tag(0x3006, 0x0026), gdcm::VR::LO, name);
    dicomrt::Put(roi, gdcm::Tag(0x3006, 0x0036), gdcm::VR::CS, "AUTOMATIC");
    rois.push_back(roi);
    text += "|" + name + "|";
    contourItems.push_back(RoiContourItem(number, contours, series, text));
    gdcm::DataSet observation;
    dicomrt::Put(observation, gdcm::Tag(0x3006, 0x0082), gdcm::VR::IS, std::to_string(number));
    dicomrt::Put(observation, gdcm::Tag(0x3006, 0x0084), gdcm::VR::IS, std::to_string(number));
    dicomrt::Put(observation, gdcm::Tag(0x3006, 0x00a4), gdcm::VR::CS, "ORGAN");
    dicomrt::Put(observation, gdcm::Tag(0x3006, 0x00a6), gdcm::VR::PN, "");
    observations.push_back(observation);
  }
  if (rois.empty())
  {
    bmr::Fail(Where, "no label of the ROI map holds a voxel of the label map: there is no structure to write");
  }

  gdcm::DataSet ds;
  dicomrt::PutCommonModules(ds, series, RTStructStorage, "RTSTRUCT", text);
  dicomrt::Put(ds, gdcm::Tag(0x3006, 0x0002), gdcm::VR::SH, "biomechreg");
  dicomrt::Put(ds, gdcm::Tag(0x3006, 0x0008), gdcm::VR::DA, "");
  dicomrt::Put(ds, gdcm::Tag(0x3006, 0x0009), gdcm::VR::TM, "");
  dicomrt::PutSequence(ds, gdcm::Tag(0x3006, 0x0010), { FrameReference(series) });
  dicomrt::PutSequence(ds, gdcm::Tag(0x3006, 0x0020), rois);
  dicomrt::PutSequence(ds, gdcm::Tag(0x3006, 0x0039), contourItems);
  dicomrt::PutSequence(ds, gdcm::Tag(0x3006, 0x0080), observations);
  dicomrt::WriteDataSetAtomically(ds, path, Where);
}

} // namespace itk

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
// A displacement field as a DICOM Deformable Spatial Registration object (PS3.3 A.39, C.20.3) and back.
#include "itkDicomRT.h"
#include "itkDicomRTWriters.h"

#include "bmrError.h"
#include "itkDicomRTCommon.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkImageRegionIteratorWithIndex.h"

#include "gdcmReader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <limits>
#include <sstream>

namespace itk {
namespace {
constexpr const char * WriteWhere = "WriteDeformableSpatialRegistration";
constexpr const char * ReadWhere = "ReadDeformableSpatialRegistration";
constexpr const char * DeformableRegistrationStorage = "1.2.840.10008.5.1.4.1.1.66.3";
const gdcm::Tag        DeformableRegistrationSequenceTag(0x0064, 0x0002);
const gdcm::Tag        SourceFrameOfReferenceUIDTag(0x0064, 0x0003);
const gdcm::Tag        GridSequenceTag(0x0064, 0x0005);
const gdcm::Tag        GridDimensionsTag(0x0064, 0x0007);
const gdcm::Tag        GridResolutionTag(0x0064, 0x0008);
const gdcm::Tag        VectorGridDataTag(0x0064, 0x0009);
const gdcm::Tag        PreMatrixSequenceTag(0x0064, 0x000f);
const gdcm::Tag        PostMatrixSequenceTag(0x0064, 0x0010);
const gdcm::Tag        MatrixTag(0x3006, 0x00c6);
const gdcm::Tag        MatrixTypeTag(0x0070, 0x030c);
const gdcm::Tag        ImagePositionTag(0x0020, 0x0032);
const gdcm::Tag        ImageOrientationTag(0x0020, 0x0037);
const gdcm::Tag        FrameOfReferenceUIDTag(0x0020, 0x0052);

/** A binary element (UL, FD, OF) from \a count values of \a T. */
template<typename T>
void
PutBinary(gdcm::DataSet & ds, const gdcm::Tag & tag, const gdcm::VR & vr, const T * values, std::size_t count)
{
  gdcm::DataElement element(tag);
  element.SetVR(vr);
  element.SetByteValue(reinterpret_cast<const char *>(values), static_cast<std::uint32_t>(count * sizeof(T)));
  ds.Replace(element);
}

/** Whether the grid's third axis runs along (+1) or against (-1) the row x column normal; fails on an oblique one. */
int
SliceSense(const DicomRTDisplacementFieldType * field)
{
  const int sense = dicomrt::SliceAxisSense(field->GetDirection());
  if (sense == 0)
  {
    bmr::FailInput(WriteWhere, "the field's slices are not perpendicular to its rows and columns (an oblique stack)");
  }
  return sense;
}

/** The identity as a rigid Frame of Reference Transformation Matrix item: the field carries the whole mapping. */
gdcm::DataSet
IdentityMatrixItem()
{
  const double  identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
  gdcm::DataSet item;
  dicomrt::Put(item, MatrixTag, gdcm::VR::DS, dicomrt::DecimalStrings(identity, 16));
  dicomrt::Put(item, MatrixTypeTag, gdcm::VR::CS, "RIGID");
  return item;
}

/** The Deformable Registration Grid item: the field's grid (slices along the normal) and its vectors [mm] as
 * 32-bit floats, x fastest; fails on a non-finite vector. */
gdcm::DataSet
GridItem(const DicomRTDisplacementFieldType * field, std::uint64_t & checksum)
{
  const int    sense = SliceSense(field);
  const auto & region = field->GetLargestPossibleRegion();
  const auto & D = field->GetDirection();
  auto         first = region.GetIndex();
  if (sense < 0) // the last slice first, so that k runs along the normal as DICOM's grid does
  {
    first[2] += static_cast<IndexValueType>(region.GetSize(2)) - 1;
  }
  Point<double, 3> origin;
  field->TransformIndexToPhysicalPoint(first, origin);
  const double        orientation[6] = { D(0, 0), D(1, 0), D(2, 0), D(0, 1), D(1, 1), D(2, 1) };
  const std::uint32_t dimensions[3] = { std::uint32_t(region.GetSize(0)),
                                        std::uint32_t(region.GetSize(1)),
                                        std::uint32_t(region.GetSize(2)) };
  const double        resolution[3] = { field->GetSpacing()[0], field->GetSpacing()[1], field->GetSpacing()[2] };
  std::vector<float>  vectors(3 * region.GetNumberOfPixels());
  for (ImageRegionConstIteratorWithIndex<DicomRTDisplacementFieldType> it(field, region); !it.IsAtEnd(); ++it)
  {
    const auto &       u = it.Get();
    const auto         index = it.GetIndex() - region.GetIndex();
    const std::int64_t k = sense > 0 ? index[2] : std::int64_t(dimensions[2]) - 1 - index[2];
    const std::size_t  at = 3 * ((std::size_t(k) * dimensions[1] + std::size_t(index[1])) * dimensions[0] + index[0]);
    for (unsigned int c = 0; c < 3; ++c)
    {
      if (!std::isfinite(u[c]))
      {
        std::ostringstream os;
        os << "the field at voxel " << it.GetIndex() << " is not finite";
        bmr::FailInput(WriteWhere, os.str());
      }
      vectors[at + c] = static_cast<float>(u[c]);
    }
  }
  for (float v : vectors) // the contents, for the derived UIDs
  {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    checksum = (checksum ^ bits) * 1099511628211ULL;
  }
  gdcm::DataSet item;
  dicomrt::Put(item, ImageOrientationTag, gdcm::VR::DS, dicomrt::DecimalStrings(orientation, 6));
  dicomrt::Put(item, ImagePositionTag, gdcm::VR::DS, dicomrt::DecimalStrings(origin.GetDataPointer(), 3));
  PutBinary(item, GridDimensionsTag, gdcm::VR::UL, dimensions, 3);
  PutBinary(item, GridResolutionTag, gdcm::VR::FD, resolution, 3);
  PutBinary(item, VectorGridDataTag, gdcm::VR::OF, vectors.data(), vectors.size());
  return item;
}

/** References (class, instance) to every image of \a series. */
std::vector<gdcm::DataSet>
ImageReferences(const dicomrt::ReferencedSeries & series)
{
  std::vector<gdcm::DataSet> items;
  for (const auto & image : series.images)
  {
    gdcm::DataSet item;
    dicomrt::Put(item, gdcm::Tag(0x0008, 0x1150), gdcm::VR::UI, image.sopClassUID);
    dicomrt::Put(item, gdcm::Tag(0x0008, 0x1155), gdcm::VR::UI, image.sopInstanceUID);
    items.push_back(item);
  }
  return items;
}

/** The Common Instance Reference module: the moving series, in this study or (its own study UID) another. */
void
PutCommonInstanceReference(gdcm::DataSet &                   ds,
                           const dicomrt::ReferencedSeries & fixed,
                           const dicomrt::ReferencedSeries & moving)
{
  gdcm::DataSet series;
  dicomrt::Put(series, gdcm::Tag(0x0020, 0x000e), gdcm::VR::UI, moving.seriesInstanceUID);
  dicomrt::PutSequence(series, gdcm::Tag(0x0008, 0x114a), ImageReferences(moving));
  const gdcm::Tag   studyTag(0x0020, 0x000d);
  const std::string movingStudy = dicomrt::StringValue(moving.patientAndStudy, studyTag);
  if (movingStudy == dicomrt::StringValue(fixed.patientAndStudy, studyTag))
  {
    dicomrt::PutSequence(ds, gdcm::Tag(0x0008, 0x1115), { series });
    return;
  }
  gdcm::DataSet study;
  dicomrt::Put(study, studyTag, gdcm::VR::UI, movingStudy);
  dicomrt::PutSequence(study, gdcm::Tag(0x0008, 0x1115), { series });
  dicomrt::PutSequence(ds, gdcm::Tag(0x0008, 0x1200), { study });
}

/** Content Date and Time: now (UTC), or SOURCE_DATE_EPOCH's when set (reproducible files). */
void
PutContentDateTime(gdcm::DataSet & ds)
{
  const char *      epoch = std::getenv("SOURCE_DATE_EPOCH");
  const std::time_t when = epoch != nullptr ? std::time_t(std::strtoll(epoch, nullptr, 10)) : std::time(nullptr);
  std::tm           utc{};
  gmtime_r(&when, &utc);
  char date[16], time[16];
  std::strftime(date, sizeof(date), "%Y%m%d", &utc);
  std::strftime(time, sizeof(time), "%H%M%S", &utc);
  dicomrt::Put(ds, gdcm::Tag(0x0008, 0x0023), gdcm::VR::DA, date);
  dicomrt::Put(ds, gdcm::Tag(0x0008, 0x0033), gdcm::VR::TM, time);
}
} // namespace

void
WriteDeformableSpatialRegistration(const DicomRTDisplacementFieldType * field,
                                   const std::string &                  fixedSeries,
                                   const std::string &                  movingSeries,
                                   const std::string &                  path)
{
  if (field == nullptr)
  {
    bmr::FailInput(WriteWhere, "no displacement field");
  }
  if (3 * 4 * double(field->GetLargestPossibleRegion().GetNumberOfPixels()) >= double(0xfffffffeu))
  {
    bmr::FailInput(WriteWhere, "the field has more vectors than a DICOM element holds (4 GiB)");
  }
  const dicomrt::ReferencedSeries fixed = dicomrt::ReadReferencedSeries(fixedSeries, WriteWhere);
  const dicomrt::ReferencedSeries moving = dicomrt::ReadReferencedSeries(movingSeries, WriteWhere);
  std::uint64_t                   checksum = 1469598103934665603ULL;
  const gdcm::DataSet             grid = GridItem(field, checksum);

  gdcm::DataSet registration;
  dicomrt::PutSequence(registration, gdcm::Tag(0x0008, 0x1140), ImageReferences(moving));
  dicomrt::Put(registration, SourceFrameOfReferenceUIDTag, gdcm::VR::UI, moving.frameOfReferenceUID);
  dicomrt::PutSequence(registration, GridSequenceTag, { grid });
  dicomrt::PutSequence(registration, PreMatrixSequenceTag, { IdentityMatrixItem() });
  dicomrt::PutSequence(registration, PostMatrixSequenceTag, { IdentityMatrixItem() });
  dicomrt::PutSequence(registration, gdcm::Tag(0x0070, 0x030d), {}); // Registration Type Code: type 2, empty

  gdcm::DataSet ds;
  dicomrt::PutCommonModules(ds,
                            fixed,
                            DeformableRegistrationStorage,
                            "REG",
                            std::to_string(checksum) + " " + moving.seriesInstanceUID + " " +
                              dicomrt::StringValue(grid, ImagePositionTag));
  dicomrt::Put(ds, gdcm::Tag(0x0018, 0x1000), gdcm::VR::LO, "0");                       // Device Serial Number
  dicomrt::Put(ds, gdcm::Tag(0x0018, 0x1020), gdcm::VR::LO, "biomechreg " BMR_VERSION); // Software Versions
  dicomrt::Put(ds, gdcm::Tag(0x0020, 0x0013), gdcm::VR::IS, "1");
  dicomrt::Put(ds, gdcm::Tag(0x0020, 0x0060), gdcm::VR::CS, ""); // Laterality: type 2C of General Series, unknown
  dicomrt::Put(ds, gdcm::Tag(0x0070, 0x0080), gdcm::VR::CS, "BIOMECHREG");
  dicomrt::Put(ds, gdcm::Tag(0x0070, 0x0081), gdcm::VR::LO, "biomechanical fixed -> moving field");
  dicomrt::Put(ds, gdcm::Tag(0x0070, 0x0084), gdcm::VR::PN, "");
  PutContentDateTime(ds);
  dicomrt::PutSequence(ds, DeformableRegistrationSequenceTag, { registration });
  PutCommonInstanceReference(ds, fixed, moving);
  dicomrt::WriteDataSetAtomically(ds, path, WriteWhere);
}

namespace {
const std::string ReadKind = "deformable registration";

/** The one item of the sequence \a tag of \a ds; fails naming the file when there is none or several. */
const gdcm::DataSet &
OnlyItem(const gdcm::DataSet & ds, const gdcm::Tag & tag, const std::string & name, const std::string & path)
{
  const auto sequence = dicomrt::Sequence(ds, tag);
  if (!sequence)
  {
    dicomrt::FailFile(ReadWhere, ReadKind, path, "no " + name);
  }
  if (sequence->GetNumberOfItems() != 1)
  {
    dicomrt::FailFile(ReadWhere,
                      ReadKind,
                      path,
                      name + " holds " + std::to_string(sequence->GetNumberOfItems()) + " items; one is read");
  }
  return sequence->GetItem(1).GetNestedDataSet();
}

/** The \a count values of a binary element (UL, FD, OF) of \a ds; fails naming the file on another length. */
template<typename T>
std::vector<T>
BinaryValues(const gdcm::DataSet & ds,
             const gdcm::Tag &     tag,
             std::size_t           count,
             const std::string &   name,
             const std::string &   path)
{
  const gdcm::ByteValue * bytes = ds.FindDataElement(tag) ? ds.GetDataElement(tag).GetByteValue() : nullptr;
  if (bytes == nullptr || bytes->GetLength() != count * sizeof(T))
  {
    dicomrt::FailFile(ReadWhere, ReadKind, path, name + " missing or not " + std::to_string(count) + " values");
  }
  std::vector<T> values(count);
  std::memcpy(values.data(), bytes->GetPointer(), count * sizeof(T));
  return values;
}

/** \a count decimal numbers at \a tag (dicomrt::FileNumbers()). */
std::vector<double>
Numbers(const gdcm::DataSet & ds,
        const gdcm::Tag &     tag,
        std::size_t           count,
        const std::string &   name,
        const std::string &   path)
{
  return dicomrt::FileNumbers(ds, tag, name, count, ReadWhere, ReadKind, path);
}

/** Refuses a pre- or post-deformation matrix other than the identity (the field is read as the whole mapping). */
void
CheckIdentityMatrix(const gdcm::DataSet & item,
                    const gdcm::Tag &     tag,
                    const std::string &   name,
                    const std::string &   path)
{
  if (!dicomrt::Sequence(item, tag))
  {
    return;
  }
  const std::vector<double> m = Numbers(OnlyItem(item, tag, name, path), MatrixTag, 16, name + "'s matrix", path);
  for (unsigned int i = 0; i < 16; ++i)
  {
    if (std::abs(m[i] - (i % 5 == 0 ? 1.0 : 0.0)) > 1e-6)
    {
      dicomrt::FailFile(ReadWhere, ReadKind, path, name + " is not the identity (not supported)");
    }
  }
}

/** The field on the grid of a Deformable Registration Grid item. */
DicomRTDisplacementFieldType::Pointer
FieldOfGrid(const gdcm::DataSet & grid, const std::string & path)
{
  const auto        orientation = Numbers(grid, ImageOrientationTag, 6, "Image Orientation (Patient)", path);
  const auto        position = Numbers(grid, ImagePositionTag, 3, "Image Position (Patient)", path);
  const auto        dimensions = BinaryValues<std::uint32_t>(grid, GridDimensionsTag, 3, "Grid Dimensions", path);
  const auto        resolution = BinaryValues<double>(grid, GridResolutionTag, 3, "Grid Resolution", path);
  const std::size_t count = std::size_t(dimensions[0]) * dimensions[1] * dimensions[2];
  const auto        vectors = BinaryValues<float>(grid, VectorGridDataTag, 3 * count, "Vector Grid Data", path);
  auto              field = DicomRTDisplacementFieldType::New();
  DicomRTDisplacementFieldType::SizeType      size = { { dimensions[0], dimensions[1], dimensions[2] } };
  DicomRTDisplacementFieldType::SpacingType   spacing;
  DicomRTDisplacementFieldType::PointType     origin;
  DicomRTDisplacementFieldType::DirectionType direction;
  std::array<double, 3>                       r, c, normal;
  if (!dicomrt::OrientationAxes(orientation, r, c, normal))
  {
    dicomrt::FailFile(ReadWhere, ReadKind, path, "Image Orientation (Patient) is not two orthogonal unit vectors");
  }
  for (unsigned int a = 0; a < 3; ++a)
  {
    if (!(resolution[a] > 0.0) || dimensions[a] == 0)
    {
      dicomrt::FailFile(ReadWhere, ReadKind, path, "an empty grid or a resolution that is not positive");
    }
    spacing[a] = resolution[a];
    origin[a] = position[a];
    direction(a, 0) = r[a];
    direction(a, 1) = c[a];
    direction(a, 2) = normal[a];
  }
  field->SetRegions(size);
  field->SetSpacing(spacing);
  field->SetOrigin(origin);
  field->SetDirection(direction);
  field->Allocate();
  if (!std::all_of(vectors.begin(), vectors.end(), [](float x) { return std::isfinite(x); }))
  {
    dicomrt::FailFile(ReadWhere, ReadKind, path, "Vector Grid Data holds a value that is not finite");
  }
  const float * v = vectors.data();
  for (ImageRegionIteratorWithIndex<DicomRTDisplacementFieldType> it(field, field->GetLargestPossibleRegion());
       !it.IsAtEnd();
       ++it, v += 3) // x fastest, as the grid stores them
  {
    it.Set(DicomRTDisplacementFieldType::PixelType(std::array<double, 3>{ { v[0], v[1], v[2] } }.data()));
  }
  return field;
}
} // namespace

DicomDeformableRegistration
ReadDeformableSpatialRegistration(const std::string & path)
{
  dicomrt::CheckDicomFile(ReadWhere, ReadKind, path);
  gdcm::Reader reader;
  dicomrt::ReadParsedFile(reader, ReadWhere, ReadKind, path);
  const gdcm::DataSet & ds = reader.GetFile().GetDataSet();
  if (dicomrt::StringValue(ds, gdcm::Tag(0x0008, 0x0016)) != DeformableRegistrationStorage)
  {
    dicomrt::FailFile(ReadWhere, ReadKind, path, "not a Deformable Spatial Registration object (SOP Class UID)");
  }
  const gdcm::DataSet & registration =
    OnlyItem(ds, DeformableRegistrationSequenceTag, "Deformable Registration Sequence", path);
  CheckIdentityMatrix(registration, PreMatrixSequenceTag, "Pre Deformation Matrix Registration Sequence", path);
  CheckIdentityMatrix(registration, PostMatrixSequenceTag, "Post Deformation Matrix Registration Sequence", path);
  DicomDeformableRegistration result;
  result.registeredFrameOfReferenceUID = dicomrt::StringValue(ds, FrameOfReferenceUIDTag);
  result.sourceFrameOfReferenceUID = dicomrt::StringValue(registration, SourceFrameOfReferenceUIDTag);
  result.field =
    FieldOfGrid(OnlyItem(registration, GridSequenceTag, "Deformable Registration Grid Sequence", path), path);
  return result;
}

} // namespace itk

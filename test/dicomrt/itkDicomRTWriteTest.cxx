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
// DICOM-RT output (itkDicomRTWriters.h), driven by dicomrt/itkDicomRTWritePlastimatch.cmake on the synthetic scan
// of itkDicomRTTest (its CT made a DICOM series by plastimatch):
//   itkDicomRTWriteTest write DIR SERIES   writes DIR/ours/{rtss,rtdose}.dcm from DIR/{labels,dose}.nrrd; checks the
//                                          round trip through this project's reader, determinism and the refusals
//   itkDicomRTWriteTest check DIR          plastimatch's reading of our files (DIR/back/*.mha, DIR/back_dose.nrrd)
//                                          against the originals
#include "bmrTestUtilities.h"
#include "itkBiomechanicalImageIO.h"
#include "itkDicomRTWriters.h"
#include "itkImageRegionConstIteratorWithIndex.h"
#include "itkLinearInterpolateImageFunction.h"

#include <filesystem>
#include <fstream>
#include <iterator>

namespace {
using bmr::test::Expect;
using bmr::test::ExpectException;
using bmr::test::ToString;
using LabelImageType = itk::DicomRTLabelImageType;
using DoseImageType = itk::DicomRTDoseImageType;
using MaskImageType = itk::Image<unsigned char, 3>;

// The labels of itkDicomRTTest's scan and the ROI names written for them.
const std::map<std::int32_t, std::string> Names = { { 1, "Body" }, { 2, "prostate" }, { 3, "bladder" } };

std::map<std::string, std::int32_t>
Values()
{
  std::map<std::string, std::int32_t> values;
  for (const auto & kv : Names)
  {
    values[kv.second] = kv.first;
  }
  return values;
}

std::string
Bytes(const std::string & path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/** Voxels whose labels differ between \a a and \a b (same grid). */
std::size_t
DifferingVoxels(const LabelImageType * a, const LabelImageType * b)
{
  std::size_t n = 0;
  for (itk::ImageRegionConstIteratorWithIndex<LabelImageType> it(a, a->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    n += it.Get() != b->GetPixel(it.GetIndex()) ? 1 : 0;
  }
  return n;
}

/** Largest |a - b| [Gy], \a b read at \a a's voxel centres (linear interpolation when the grids differ). */
double
WorstDoseError(const DoseImageType * a, const DoseImageType * b)
{
  auto interpolator = itk::LinearInterpolateImageFunction<DoseImageType, double>::New();
  interpolator->SetInputImage(b);
  double worst = 0.0;
  for (itk::ImageRegionConstIteratorWithIndex<DoseImageType> it(a, a->GetLargestPossibleRegion()); !it.IsAtEnd(); ++it)
  {
    DoseImageType::PointType p;
    a->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    worst = std::max(worst,
                     interpolator->IsInsideBuffer(p) ? std::abs(interpolator->Evaluate(p) - it.Get())
                                                     : std::numeric_limits<double>::infinity());
  }
  return worst;
}

bool
CheckRoundTrip(const std::string & dir, const std::string & series)
{
  bool              ok = true;
  const auto        labels = itk::ReadBiomechanicalImage<LabelImageType>(dir + "/labels.nrrd", "label image");
  const auto        dose = itk::ReadBiomechanicalImage<DoseImageType>(dir + "/dose.nrrd", "dose");
  const std::string rtss = dir + "/ours/rtss.dcm", rtdose = dir + "/ours/rtdose.dcm";
  std::filesystem::create_directories(dir + "/ours");
  itk::WriteRTStruct(labels, Names, series, rtss);
  itk::WriteRTStruct(labels, Names, series, dir + "/ours/rtss_again.dcm");
  itk::WriteRTDose(dose, series, rtdose);
  itk::WriteRTDose(dose, series, dir + "/ours/rtdose_again.dcm");
  ok &=
    Expect(Bytes(rtss) == Bytes(dir + "/ours/rtss_again.dcm") && Bytes(rtdose) == Bytes(dir + "/ours/rtdose_again.dcm"),
           "the same inputs write the same bytes (derived UIDs, no dates)");
  ok &= Expect(itk::ReadDicomModality(rtss) == "RTSTRUCT" && itk::ReadDicomModality(rtdose) == "RTDOSE",
               "the files' modalities are RTSTRUCT and RTDOSE");
  // Exact: the contours run through the midpoints of voxel edges, never through a voxel centre, so the even-odd
  // test at the centres gives back every voxel (holes and two contours per slice included).
  const auto        back = itk::ReadRTStructAsLabelImage(rtss, labels, Values());
  const std::size_t differing = DifferingVoxels(labels, back);
  std::cout << "  RTSTRUCT round trip: " << differing << " voxels differ" << std::endl;
  ok &= Expect(differing == 0,
               "our reader gives back every voxel of the written label map (" + ToString(differing) +
                 " differ; tolerance 0)");
  // The float dose holds ~7 significant digits (4.7e-6 Gy at 78 Gy); the 32-bit quantization adds < 1e-8 Gy.
  const double worst = WorstDoseError(dose, itk::ReadRTDose(rtdose));
  std::cout << "  RTDOSE round trip: max |error| " << worst << " Gy" << std::endl;
  ok &= Expect(worst <= 1e-5, "RTDOSE round trip within 1e-5 Gy (measured " + ToString(worst) + ")");
  return ok;
}

bool
CheckRefusals(const std::string & dir, const std::string & series)
{
  bool              ok = true;
  const auto        labels = itk::ReadBiomechanicalImage<LabelImageType>(dir + "/labels.nrrd", "label image");
  const auto        dose = itk::ReadBiomechanicalImage<DoseImageType>(dir + "/dose.nrrd", "dose");
  const std::string target = dir + "/refused.dcm";

  auto shifted = LabelImageType::New();
  shifted->Graft(labels);
  auto origin = labels->GetOrigin();
  origin[2] += 1.25; // half a slice: no slice of the series
  shifted->SetOrigin(origin);
  ok &= ExpectException(
    "labels off the series' slices",
    [&] { itk::WriteRTStruct(shifted, Names, series, target); },
    "is no slice of the reference series");
  auto turned = LabelImageType::New();
  turned->Graft(labels);
  LabelImageType::DirectionType D;
  D.Fill(0.0);
  D(0, 1) = 1.0;
  D(1, 0) = -1.0;
  D(2, 2) = 1.0;
  turned->SetDirection(D);
  ok &= ExpectException(
    "labels turned in-plane",
    [&] { itk::WriteRTStruct(turned, Names, series, target); },
    "not oriented as the images of the reference series");
  ok &= ExpectException(
    "a directory without a series",
    [&] { itk::WriteRTStruct(labels, Names, dir + "/masks", target); },
    "holds 0 DICOM image series");
  ok &= ExpectException(
    "no directory", [&] { itk::WriteRTDose(dose, dir + "/missing", target); }, "is not a directory");
  ok &= ExpectException(
    "a name twice",
    [&] {
      itk::WriteRTStruct(labels, { { 1, "Body" }, { 2, "body " }, { 3, "Body" } }, series, target);
    },
    "is given to two labels");
  ok &= ExpectException(
    "an empty name",
    [&] {
      itk::WriteRTStruct(labels, { { 1, " " } }, series, target);
    },
    "must have 1 to 64 characters");
  ok &= ExpectException(
    "no labelled voxel",
    [&] {
      itk::WriteRTStruct(labels, { { 7, "other" } }, series, target);
    },
    "no label of the ROI map holds a voxel");
  const float kept = dose->GetPixel({ { 3, 4, 5 } });
  dose->SetPixel({ { 3, 4, 5 } }, -1.0f);
  ok &= ExpectException(
    "a negative dose", [&] { itk::WriteRTDose(dose, series, target); }, "[3, 4, 5]");
  dose->SetPixel({ { 3, 4, 5 } }, kept);
  ok &= ExpectException(
    "a missing output directory",
    [&] { itk::WriteRTDose(dose, series, dir + "/no_such_directory/rtdose.dcm"); },
    "cannot write");
  ok &= Expect(!std::filesystem::exists(target), "no refused call left a file behind");
  return ok;
}

/** The voxels of \a value in \a labels with, slice by slice, every hole filled: the voxels that no 4-connected
 * path outside the region links to the slice's border. */
MaskImageType::Pointer
FilledSlices(const LabelImageType * labels, std::int32_t value)
{
  auto mask = MaskImageType::New();
  mask->CopyInformation(labels);
  mask->SetRegions(labels->GetLargestPossibleRegion());
  mask->Allocate(true);
  const auto & size = labels->GetLargestPossibleRegion().GetSize();
  for (itk::IndexValueType k = 0; k < itk::IndexValueType(size[2]); ++k)
  {
    std::vector<char>                                                outside(size[0] * size[1], 0);
    std::vector<std::pair<itk::IndexValueType, itk::IndexValueType>> open;
    const auto visit = [&](itk::IndexValueType i, itk::IndexValueType j) {
      if (i >= 0 && j >= 0 && i < itk::IndexValueType(size[0]) && j < itk::IndexValueType(size[1]) &&
          !outside[j * size[0] + i] && labels->GetPixel({ { i, j, k } }) != value)
      {
        outside[j * size[0] + i] = 1;
        open.push_back({ i, j });
      }
    };
    for (itk::IndexValueType i = 0; i < itk::IndexValueType(size[0]); ++i)
    {
      visit(i, 0);
      visit(i, itk::IndexValueType(size[1]) - 1);
    }
    for (itk::IndexValueType j = 0; j < itk::IndexValueType(size[1]); ++j)
    {
      visit(0, j);
      visit(itk::IndexValueType(size[0]) - 1, j);
    }
    while (!open.empty())
    {
      const auto [i, j] = open.back();
      open.pop_back();
      visit(i + 1, j);
      visit(i - 1, j);
      visit(i, j + 1);
      visit(i, j - 1);
    }
    for (itk::IndexValueType j = 0; j < itk::IndexValueType(size[1]); ++j)
    {
      for (itk::IndexValueType i = 0; i < itk::IndexValueType(size[0]); ++i)
      {
        mask->SetPixel({ { i, j, k } }, outside[j * size[0] + i] ? 0 : 1);
      }
    }
  }
  return mask;
}

/** Dice of plastimatch's mask of each ROI against the label map's region with its holes filled: plastimatch 1.9.4
 * fills every contour (a ring is read as a disc, also from the RTSTRUCT it writes itself), where the even-odd
 * rule of our reader keeps the holes. */
bool
CheckPlastimatchReading(const std::string & dir)
{
  bool       ok = true;
  const auto labels = itk::ReadBiomechanicalImage<LabelImageType>(dir + "/labels.nrrd", "label image");
  for (const auto & kv : Names)
  {
    const auto  mask = itk::ReadBiomechanicalImage<MaskImageType>(dir + "/back/" + kv.second + ".mha", kv.second);
    const auto  filled = FilledSlices(labels, kv.first);
    std::size_t both = 0, inFilled = 0, inMask = 0;
    for (itk::ImageRegionConstIteratorWithIndex<MaskImageType> it(filled, filled->GetLargestPossibleRegion());
         !it.IsAtEnd();
         ++it)
    {
      MaskImageType::PointType p;
      filled->TransformIndexToPhysicalPoint(it.GetIndex(), p);
      MaskImageType::IndexType index;
      const bool               inside = mask->TransformPhysicalPointToIndex(p, index) && mask->GetPixel(index) != 0;
      both += inside && it.Get() ? 1 : 0;
      inFilled += it.Get() ? 1 : 0;
      inMask += inside ? 1 : 0;
    }
    const double dice = 2.0 * double(both) / double(inFilled + inMask);
    std::cout << "  plastimatch reads ROI " << kv.second << ": Dice " << dice << " against its filled region ("
              << inFilled << " voxels)" << std::endl;
    ok &= Expect(dice >= 0.999,
                 "plastimatch's mask of " + kv.second + " has Dice >= 0.999 against the filled region " + "(measured " +
                   ToString(dice) + "; its rule at the contours' edges may differ)");
  }
  const auto   original = itk::ReadBiomechanicalImage<DoseImageType>(dir + "/dose.nrrd", "dose");
  const double worst =
    WorstDoseError(original, itk::ReadBiomechanicalImage<DoseImageType>(dir + "/back_dose.nrrd", "dose"));
  std::cout << "  plastimatch reads the RTDOSE: max |error| " << worst << " Gy" << std::endl;
  // plastimatch reads the dose into floats and so does this test: two roundings of ~4.7e-6 Gy at 78 Gy.
  ok &= Expect(worst <= 2e-5, "plastimatch reads our RTDOSE within 2e-5 Gy (measured " + ToString(worst) + ")");
  return ok;
}
} // namespace

int
itkDicomRTWriteTest(int argc, char * argv[])
{
  const std::string mode = argc > 2 ? argv[1] : "";
  if (!((mode == "write" && argc == 4) || (mode == "check" && argc == 3)))
  {
    std::cerr << "usage: " << argv[0] << " write DIR SERIES | check DIR" << std::endl;
    return EXIT_FAILURE;
  }
  bool ok = true;
  try
  {
    ok = mode == "write" ? CheckRoundTrip(argv[2], argv[3]) & CheckRefusals(argv[2], argv[3])
                         : CheckPlastimatchReading(argv[2]);
  }
  catch (const std::exception & e)
  {
    std::cerr << "FAIL: unexpected exception: " << e.what() << std::endl;
    return EXIT_FAILURE;
  }
  std::cout << (ok ? "itkDicomRTWriteTest passed" : "itkDicomRTWriteTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

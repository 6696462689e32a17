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
// DICOM-RT input against an independent writer (plastimatch), driven by dicomrt/itkDicomRTPlastimatch.cmake:
//   itkDicomRTTest make DIR                      CT, label map, one uint8 mask per organ, dose [Gy] (NRRD)
//   itkDicomRTTest check DIR RTSTRUCT RTDOSE     our readers against the originals, and the refusals
//   itkDicomRTTest masks LABELS DIR name=value.. one uint8 mask per label of a label map (the CLI check)
// Bad files are made from plastimatch's with GDCM (a removed or changed attribute, a truncated copy).
#include "bmrTestUtilities.h"
#include "itkBiomechanicalImageIO.h"
#include "itkDicomRT.h"
#include "itkLinearInterpolateImageFunction.h"

#include "gdcmReader.h"
#include "gdcmWriter.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <random>

namespace {
using bmr::test::Expect;
using LabelImageType = itk::DicomRTLabelImageType;
using DoseImageType = itk::DicomRTDoseImageType;
using CTImageType = itk::Image<short, 3>;
using MaskImageType = itk::Image<unsigned char, 3>;

// The synthetic scan: anisotropic voxels and an origin off zero, so that index and physical space differ.
constexpr unsigned int Size[3] = { 48, 40, 16 };
constexpr double       Spacing[3] = { 1.2, 1.0, 2.5 };    // mm
constexpr double       Origin[3] = { -30.0, -22.0, 5.0 }; // LPS mm
constexpr double       MaximumDose = 78.0;                // Gy

// Labels of the synthetic scan; the masks' file names (plastimatch's structure names) are written in other
// cases than the names of the map the test reads them with ("Body" vs " body "), to check the name matching.
constexpr std::int32_t BodyLabel = 1, ProstateLabel = 2, BladderLabel = 3;

template<typename TImage>
typename TImage::Pointer
MakeImage(const unsigned int size[3], const double origin[3])
{
  auto                         image = TImage::New();
  typename TImage::RegionType  region;
  typename TImage::PointType   o;
  typename TImage::SpacingType s;
  for (unsigned int a = 0; a < 3; ++a)
  {
    region.SetSize(a, size[a]);
    o[a] = origin[a];
    s[a] = Spacing[a];
  }
  image->SetRegions(region);
  image->SetOrigin(o);
  image->SetSpacing(s);
  image->Allocate(true);
  return image;
}

/** The label of a point [mm]: a body (an ellipse over slices 1..14) holding a bladder that is a ring in every
 * slice (its lumen is a hole of the ROI: body in the label map) and a prostate of two separate discs per slice
 * (two contours of one ROI in one slice). Organs win over the body. */
std::int32_t
LabelAt(const itk::Point<double, 3> & p, long slice)
{
  const double cx = Origin[0] + 0.5 * (Size[0] - 1) * Spacing[0];
  const double cy = Origin[1] + 0.5 * (Size[1] - 1) * Spacing[1];
  const double bladderR = std::hypot(p[0] - (cx - 5.0), p[1] - (cy + 2.0));
  const double discA = std::hypot(p[0] - (cx + 13.0), p[1] - (cy - 7.0));
  const double discB = std::hypot(p[0] - (cx + 13.0), p[1] - (cy + 7.0));
  if (slice >= 4 && slice <= 10 && bladderR >= 5.0 && bladderR < 9.0)
  {
    return BladderLabel;
  }
  if (slice >= 3 && slice <= 12 && (discA < 3.2 || discB < 3.2))
  {
    return ProstateLabel;
  }
  const double ex = (p[0] - cx) / 24.0, ey = (p[1] - cy) / 17.0;
  return slice >= 1 && slice <= 14 && ex * ex + ey * ey < 1.0 ? BodyLabel : 0;
}

/** A smooth dose [Gy]: a Gaussian of 15 mm about the grid's centre, maximum MaximumDose. */
float
DoseAt(const itk::Point<double, 3> & p)
{
  double r2 = 0.0;
  for (unsigned int a = 0; a < 3; ++a)
  {
    const double c = Origin[a] + 0.5 * (Size[a] - 1) * Spacing[a];
    r2 += (p[a] - c) * (p[a] - c);
  }
  return static_cast<float>(MaximumDose * std::exp(-r2 / (2.0 * 15.0 * 15.0)));
}

int
MakeInputs(const std::string & dir)
{
  std::filesystem::create_directories(dir + "/masks");
  auto ct = MakeImage<CTImageType>(Size, Origin);
  auto labels = MakeImage<LabelImageType>(Size, Origin);
  auto dose = MakeImage<DoseImageType>(Size, Origin);
  auto body = MakeImage<MaskImageType>(Size, Origin);
  auto bladder = MakeImage<MaskImageType>(Size, Origin);
  auto prostate = MakeImage<MaskImageType>(Size, Origin);
  for (itk::ImageRegionIteratorWithIndex<LabelImageType> it(labels, labels->GetBufferedRegion()); !it.IsAtEnd(); ++it)
  {
    itk::Point<double, 3> p;
    labels->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    const std::int32_t label = LabelAt(p, it.GetIndex()[2]);
    it.Set(label);
    ct->SetPixel(it.GetIndex(), label == 0 ? -1000 : 40 * label);
    dose->SetPixel(it.GetIndex(), DoseAt(p));
    // The body's mask is the whole outline, organs included: the RTSTRUCT's ROIs overlap.
    body->SetPixel(it.GetIndex(), label != 0);
    bladder->SetPixel(it.GetIndex(), label == BladderLabel);
    prostate->SetPixel(it.GetIndex(), label == ProstateLabel);
  }
  itk::WriteImageAtomically(ct.GetPointer(), dir + "/ct.nrrd", 0);
  itk::WriteImageAtomically(labels.GetPointer(), dir + "/labels.nrrd", 0);
  itk::WriteImageAtomically(dose.GetPointer(), dir + "/dose.nrrd", 0);
  itk::WriteImageAtomically(body.GetPointer(), dir + "/masks/Body.nrrd", 0);
  itk::WriteImageAtomically(bladder.GetPointer(), dir + "/masks/BLADDER.nrrd", 0);
  itk::WriteImageAtomically(prostate.GetPointer(), dir + "/masks/prostate.nrrd", 0);
  return EXIT_SUCCESS;
}

int
MakeMasks(const std::string & labelsPath, const std::string & dir, const std::vector<std::string> & entries)
{
  std::filesystem::create_directories(dir);
  const auto labels = itk::ReadBiomechanicalImage<LabelImageType>(labelsPath, "label image");
  for (const auto & entry : entries)
  {
    const auto         equals = entry.find('=');
    const std::string  name = entry.substr(0, equals);
    const std::int32_t value = std::stoi(entry.substr(equals + 1));
    auto               mask = MaskImageType::New();
    mask->CopyInformation(labels);
    mask->SetRegions(labels->GetLargestPossibleRegion());
    mask->Allocate();
    for (itk::ImageRegionIteratorWithIndex<MaskImageType> it(mask, mask->GetBufferedRegion()); !it.IsAtEnd(); ++it)
    {
      it.Set(labels->GetPixel(it.GetIndex()) == value);
    }
    itk::WriteImageAtomically(mask.GetPointer(), dir + "/" + name + ".nrrd", 0);
  }
  return EXIT_SUCCESS;
}

// ------------------------------------------------------------------------------------------ checks

double
Dice(const LabelImageType * a, const LabelImageType * b, std::int32_t label, std::size_t & countA, std::size_t & countB)
{
  std::size_t both = 0;
  countA = countB = 0;
  const std::size_t n = a->GetBufferedRegion().GetNumberOfPixels();
  for (std::size_t i = 0; i < n; ++i)
  {
    const bool inA = a->GetBufferPointer()[i] == label;
    const bool inB = b->GetBufferPointer()[i] == label;
    countA += inA;
    countB += inB;
    both += inA && inB;
  }
  return countA + countB == 0 ? 1.0 : 2.0 * static_cast<double>(both) / static_cast<double>(countA + countB);
}

bool
SameGrid(const itk::ImageBase<3> * a, const itk::ImageBase<3> * b)
{
  // 1e-4 mm: DS values are decimal text (plastimatch writes them to ~6 significant digits).
  return a->GetLargestPossibleRegion().GetSize() == b->GetLargestPossibleRegion().GetSize() &&
         a->GetOrigin().EuclideanDistanceTo(b->GetOrigin()) < 1e-4 &&
         (a->GetSpacing() - b->GetSpacing()).GetNorm() < 1e-4 &&
         (a->GetDirection().GetVnlMatrix() - b->GetDirection().GetVnlMatrix()).frobenius_norm() < 1e-6;
}

/** True when \a action throws an itk::ExceptionObject whose description holds every one of \a parts. */
bool
Refuses(const std::string & what, const std::function<void()> & action, const std::vector<std::string> & parts)
{
  try
  {
    action();
  }
  catch (const itk::ExceptionObject & e)
  {
    const std::string message = e.GetDescription();
    std::cout << "  refused, " << what << ": " << message << std::endl;
    bool ok = Expect(message.find('\n') == std::string::npos, what + ": the message is one line");
    for (const auto & p : parts)
    {
      ok &= Expect(message.find(p) != std::string::npos, what + ": the message \"" + message + "\" names " + p);
    }
    return ok;
  }
  catch (const std::exception & e)
  {
    return Expect(false, what + ": threw a std::exception that is not an itk::ExceptionObject: " + e.what());
  }
  return Expect(false, what + ": accepted");
}

/** A copy of the DICOM file \a from, changed by \a edit, written to \a to. */
void
WriteEditedCopy(const std::string & from, const std::string & to, const std::function<void(gdcm::DataSet &)> & edit)
{
  gdcm::Reader reader;
  reader.SetFileName(from.c_str());
  if (!reader.Read())
  {
    throw std::runtime_error("cannot read " + from);
  }
  edit(reader.GetFile().GetDataSet());
  gdcm::Writer writer;
  writer.SetFile(reader.GetFile());
  writer.SetFileName(to.c_str());
  if (!writer.Write())
  {
    throw std::runtime_error("cannot write " + to);
  }
}

void
ReplaceString(gdcm::DataSet & ds, const gdcm::Tag & tag, const gdcm::VR & vr, std::string value)
{
  if (value.size() % 2)
  {
    value += ' '; // DICOM values have an even length
  }
  gdcm::DataElement element(tag);
  element.SetVR(vr);
  element.SetByteValue(value.c_str(), static_cast<std::uint32_t>(value.size()));
  ds.Replace(element);
}

/** The first \a fraction of the bytes of \a from, written to \a to. */
void
WriteTruncatedCopy(const std::string & from, const std::string & to, double fraction)
{
  std::ifstream     in(from, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(to, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size() * fraction));
}

/** The original map's names, in other cases and with surrounding spaces. */
std::map<std::string, std::int32_t>
OrganMap()
{
  return { { " body ", BodyLabel }, { "Bladder", BladderLabel }, { "PROSTATE ", ProstateLabel } };
}

bool
CheckStructures(const std::string & dir, const std::string & rtstruct)
{
  bool       ok = true;
  const auto original = itk::ReadBiomechanicalImage<LabelImageType>(dir + "/labels.nrrd", "label map");
  const auto ct = itk::ReadBiomechanicalImage<CTImageType>(dir + "/ct.nrrd", "CT");

  ok &= Expect(itk::ReadDicomModality(rtstruct) == "RTSTRUCT", "ReadDicomModality(RTSTRUCT) is RTSTRUCT");
  ok &= Expect(itk::ReadDicomModality(dir + "/ct.nrrd").empty(), "ReadDicomModality(NRRD) is empty");
  ok &= Expect(itk::ReadDicomModality(dir).empty(), "ReadDicomModality(directory) is empty");
  ok &= Expect(itk::ReadDicomModality(dir + "/no_such_file.dcm").empty(), "ReadDicomModality(missing) is empty");
  auto names = itk::ReadRTStructROINames(rtstruct);
  std::sort(names.begin(), names.end());
  ok &= Expect(names == std::vector<std::string>{ "BLADDER", "Body", "prostate" },
               "ReadRTStructROINames gives the masks' file names BLADDER, Body, prostate");

  // Dice >= 0.98 per organ (the criterion). plastimatch traces each mask's slices by marching squares
  // through the midpoints between voxel centres, so the even-odd test at the centres gives the mask back
  // exactly except where a diagonal cut passes a centre; the body is checked after the overlap rule (its
  // ROI is the whole outline; the organs inside win as the smaller ROIs).
  const auto labels = itk::ReadRTStructAsLabelImage(rtstruct, ct, OrganMap());
  ok &= Expect(SameGrid(labels, ct), "the label map is on the CT's grid");
  const std::map<std::string, std::int32_t> organs{ { "body", BodyLabel },
                                                    { "bladder (a ring: holes)", BladderLabel },
                                                    { "prostate (two contours per slice)", ProstateLabel } };
  for (const auto & organ : organs)
  {
    std::size_t  read = 0, expected = 0;
    const double dice = Dice(labels, original, organ.second, read, expected);
    std::cout << "  Dice " << organ.first << ": " << std::setprecision(6) << dice << " (" << read << " voxels read, "
              << expected << " in the mask)" << std::endl;
    ok &= Expect(dice >= 0.98, "Dice of " + organ.first + " >= 0.98: " + bmr::test::ToString(dice));
  }
  std::size_t  read = 0, expected = 0;
  const double background = Dice(labels, original, 0, read, expected);
  ok &= Expect(background >= 0.98, "Dice of the background >= 0.98: " + bmr::test::ToString(background));

  // Unmapped ROIs skipped on request: the prostate's voxels fall back to the body, whose ROI covers them.
  itk::RTStructRasterizationOptions skip;
  skip.ignoreUnmappedROIs = true;
  skip.backgroundLabel = -1;
  const auto noProstate =
    itk::ReadRTStructAsLabelImage(rtstruct, ct, { { "body", BodyLabel }, { "bladder", BladderLabel } }, skip);
  std::size_t prostateVoxels = 0, prostateInOriginal = 0, minusOne = 0, zeroes = 0;
  for (std::size_t i = 0; i < original->GetBufferedRegion().GetNumberOfPixels(); ++i)
  {
    const bool wasProstate = original->GetBufferPointer()[i] == ProstateLabel;
    prostateInOriginal += wasProstate;
    prostateVoxels += wasProstate && noProstate->GetBufferPointer()[i] == BodyLabel;
    minusOne += noProstate->GetBufferPointer()[i] == -1;
    zeroes += noProstate->GetBufferPointer()[i] == 0;
  }
  ok &= Expect(prostateVoxels >= 0.98 * prostateInOriginal,
               "ignoring the prostate ROI, its voxels are body (the body ROI holds them)");
  ok &= Expect(minusOne > 0 && zeroes == 0, "backgroundLabel -1 fills the voxels outside every ROI");

  // Refusals, each naming the file (and the ROI where one is at fault).
  ok &= Refuses("an ROI the map lacks",
                [&] {
                  itk::ReadRTStructAsLabelImage(rtstruct, ct, { { "body", 1 }, { "bladder", 3 } });
                },
                { rtstruct, "ROI \"prostate\"" });
  ok &= Refuses("a map name the file lacks",
                [&] {
                  auto map = OrganMap();
                  map["rectum"] = 4;
                  itk::ReadRTStructAsLabelImage(rtstruct, ct, map);
                },
                { rtstruct, "\"rectum\"" });
  ok &= Refuses("two map names that are the same name",
                [&] {
                  auto map = OrganMap();
                  map["BODY"] = 5;
                  itk::ReadRTStructAsLabelImage(rtstruct, ct, map);
                },
                { rtstruct, "same name" });
  ok &= Refuses("a non-DICOM file",
                [&] { itk::ReadRTStructAsLabelImage(dir + "/ct.nrrd", ct, OrganMap()); },
                { dir + "/ct.nrrd", "not a DICOM file" });
  ok &= Refuses(
    "a missing file", [&] { itk::ReadRTStructROINames(dir + "/no_such_file.dcm"); }, { dir + "/no_such_file.dcm" });
  for (const double fraction : { 0.6, 0.2, 0.05 })
  {
    const std::string truncated = dir + "/truncated_" + std::to_string(static_cast<int>(100 * fraction)) + ".dcm";
    WriteTruncatedCopy(rtstruct, truncated, fraction);
    ok &= Refuses("an RTSTRUCT truncated to " + std::to_string(fraction),
                  [&] { itk::ReadRTStructAsLabelImage(truncated, ct, OrganMap()); },
                  { truncated });
  }
  const std::string noReference = dir + "/no_referenced_frame.dcm";
  WriteEditedCopy(rtstruct, noReference, [](gdcm::DataSet & ds) { ds.Remove(gdcm::Tag(0x3006, 0x0010)); });
  ok &= Refuses("no Referenced Frame of Reference Sequence",
                [&] { itk::ReadRTStructAsLabelImage(noReference, ct, OrganMap()); },
                { noReference, "Referenced Frame of Reference" });
  const std::string notStruct = dir + "/modality_ct.dcm";
  WriteEditedCopy(
    rtstruct, notStruct, [](gdcm::DataSet & ds) { ReplaceString(ds, gdcm::Tag(0x0008, 0x0060), gdcm::VR::CS, "CT"); });
  ok &= Refuses(
    "Modality CT", [&] { itk::ReadRTStructAsLabelImage(notStruct, ct, OrganMap()); }, { notStruct, "not an RTSTRUCT" });

  // Reference grids that do not cover the contours: too few slices (the body reaches slice 14), and shifted
  // in-plane by 20 mm (the body reaches within 0.6 mm of the x borders).
  // Only the body is read, so that the error names it whatever the order of the ROIs in the file.
  const std::map<std::string, std::int32_t> bodyOnly{ { " body ", BodyLabel } };
  const unsigned int                        fewSlices[3] = { Size[0], Size[1], 8 };
  const auto                                shortGrid = MakeImage<CTImageType>(fewSlices, Origin);
  ok &= Refuses("a grid with too few slices",
                [&] { itk::ReadRTStructAsLabelImage(rtstruct, shortGrid, bodyOnly, skip); },
                { rtstruct, "lies on no slice of the reference grid", "ROI \"Body\"" });
  const double shiftedOrigin[3] = { Origin[0] + 20.0, Origin[1], Origin[2] };
  const auto   shiftedGrid = MakeImage<CTImageType>(Size, shiftedOrigin);
  ok &= Refuses("a grid shifted in-plane",
                [&] { itk::ReadRTStructAsLabelImage(rtstruct, shiftedGrid, bodyOnly, skip); },
                { rtstruct, "outside the reference grid in-plane", "ROI \"Body\"" });
  ok &= Refuses("no reference grid",
                [&] { itk::ReadRTStructAsLabelImage(dir + "/ct.nrrd", nullptr, OrganMap()); },
                { dir + "/ct.nrrd", "no reference grid" });
  return ok;
}

bool
CheckDose(const std::string & dir, const std::string & rtdose, const std::string & rtstruct)
{
  bool       ok = true;
  const auto original = itk::ReadBiomechanicalImage<DoseImageType>(dir + "/dose.nrrd", "dose");
  ok &= Expect(itk::ReadDicomModality(rtdose) == "RTDOSE", "ReadDicomModality(RTDOSE) is RTDOSE");
  const auto dose = itk::ReadDoseImage(rtdose);
  const auto sameAsNrrd = itk::ReadDoseImage(dir + "/dose.nrrd");
  ok &= Expect(sameAsNrrd->GetPixel({ { 10, 11, 7 } }) == original->GetPixel({ { 10, 11, 7 } }),
               "ReadDoseImage reads a NRRD as an image in Gy");

  // plastimatch writes the dose on the grid of the dose image it is given; should it write another grid, the
  // read dose is compared at the original voxel centres through linear interpolation (the dose is smooth:
  // sigma 15 mm against voxels <= 2.5 mm), and voxels outside the written grid fail the test.
  std::cout << "  RTDOSE grid " << dose->GetLargestPossibleRegion().GetSize() << ", origin " << dose->GetOrigin()
            << ", spacing " << dose->GetSpacing() << (SameGrid(dose, original) ? " (the original grid)" : "")
            << std::endl;
  auto interpolator = itk::LinearInterpolateImageFunction<DoseImageType, double>::New();
  interpolator->SetInputImage(dose);
  double      worst = 0.0;
  std::size_t outside = 0;
  for (itk::ImageRegionConstIteratorWithIndex<DoseImageType> it(original, original->GetBufferedRegion()); !it.IsAtEnd();
       ++it)
  {
    itk::Point<double, 3> p;
    original->TransformIndexToPhysicalPoint(it.GetIndex(), p);
    if (!interpolator->IsInsideBuffer(p))
    {
      ++outside;
      continue;
    }
    worst = std::max(worst, std::abs(interpolator->Evaluate(p) - it.Get()));
  }
  // 0.5 % of the maximum (the criterion). plastimatch stores 32-bit integers with a Dose Grid
  // Scaling of 5 significant digits: the expected error is ~1e-4 of a value, far inside.
  std::cout << "  RTDOSE max |dose - original| = " << worst << " Gy = " << 100.0 * worst / MaximumDose
            << " % of the maximum; " << outside << " voxels outside the RTDOSE grid" << std::endl;
  ok &= Expect(outside == 0, "every original voxel is inside the RTDOSE grid");
  ok &= Expect(worst <= 0.005 * MaximumDose,
               "max |dose - original| <= 0.5 % of " + bmr::test::ToString(MaximumDose) +
                 " Gy: " + bmr::test::ToString(worst));

  ok &= Refuses("an RTDOSE as RTSTRUCT",
                [&] { itk::ReadRTStructAsLabelImage(rtdose, original, OrganMap()); },
                { rtdose, "not an RTSTRUCT" });
  ok &= Refuses("an RTSTRUCT as RTDOSE", [&] { itk::ReadRTDose(rtstruct); }, { rtstruct, "not an RTDOSE" });
  ok &=
    Refuses("a NRRD as RTDOSE", [&] { itk::ReadRTDose(dir + "/dose.nrrd"); }, { dir + "/dose.nrrd", "not a DICOM" });
  const std::string relative = dir + "/dose_relative.dcm";
  WriteEditedCopy(rtdose, relative, [](gdcm::DataSet & ds) {
    ReplaceString(ds, gdcm::Tag(0x3004, 0x0002), gdcm::VR::CS, "RELATIVE");
  });
  ok &= Refuses("Dose Units RELATIVE", [&] { itk::ReadRTDose(relative); }, { relative, "RELATIVE", "not GY" });
  ok &= Refuses("Dose Units RELATIVE through ReadDoseImage", [&] { itk::ReadDoseImage(relative); }, { relative });
  const std::string uneven = dir + "/dose_uneven.dcm";
  WriteEditedCopy(rtdose, uneven, [](gdcm::DataSet & ds) {
    std::ostringstream offsets;
    for (unsigned int k = 0; k < Size[2]; ++k)
    {
      offsets << (k ? "\\" : "") << (k < 5 ? 2.5 * k : 2.5 * k + 1.0); // a 3.5 mm step between frames 5 and 6
    }
    ReplaceString(ds, gdcm::Tag(0x3004, 0x000c), gdcm::VR::DS, offsets.str());
  });
  ok &= Refuses("unevenly spaced frames", [&] { itk::ReadRTDose(uneven); }, { uneven, "not evenly spaced" });
  const std::string truncated = dir + "/dose_truncated.dcm";
  WriteTruncatedCopy(rtdose, truncated, 0.7);
  ok &= Refuses("a truncated RTDOSE", [&] { itk::ReadRTDose(truncated); }, { truncated });
  return ok;
}

std::vector<char>
ReadFileBytes(const std::string & path)
{
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/** Where the File Meta Information (group 0002, explicit VR little endian after the 132-byte preamble) of the
 * Part 10 file \a bytes ends. */
std::size_t
MetaInformationEnd(const std::vector<char> & bytes)
{
  const auto  u8 = [&](std::size_t i) { return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[i])); };
  std::size_t pos = 132;
  while (pos + 8 <= bytes.size() && (u8(pos) | u8(pos + 1) << 8) == 0x0002)
  {
    const std::string vr(bytes.data() + pos + 4, 2);
    const bool        longHeader = vr == "OB" || vr == "OW" || vr == "UN" || vr == "UT" || vr == "SQ";
    pos += longHeader ? 12 + (u8(pos + 8) | u8(pos + 9) << 8 | u8(pos + 10) << 16 | u8(pos + 11) << 24)
                      : 8 + (u8(pos + 6) | u8(pos + 7) << 8);
  }
  return pos;
}

/** \a trials seeded random corruptions of \a source (1-6 bytes overwritten in [132, \a end); one in five also
 * truncated), each given to \a read: each must be read or refused with an itk::ExceptionObject naming the file,
 * never crash the process. */
bool
CheckCorruptCopies(const std::string &                              dir,
                   const std::string &                              source,
                   const std::string &                              what,
                   std::size_t                                      end,
                   const std::function<void(const std::string &)> & read,
                   std::mt19937 &                                   random)
{
  const std::vector<char> original = ReadFileBytes(source);
  end = std::min(end, original.size());
  std::size_t read_ = 0, refused = 0;
  bool        ok = true;
  for (int trial = 0; trial < 150; ++trial)
  {
    std::vector<char> bytes = original;
    const int         changes = 1 + static_cast<int>(random() % 6);
    for (int c = 0; c < changes; ++c)
    {
      bytes[132 + random() % (end - 132)] = static_cast<char>(random() % 256);
    }
    if (random() % 5 == 0)
    {
      bytes.resize(132 + random() % (bytes.size() - 132));
    }
    const std::string corrupt = dir + "/corrupt.dcm";
    std::ofstream(corrupt, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    try
    {
      read(corrupt);
      ++read_;
    }
    catch (const itk::ExceptionObject & e)
    {
      ok &= Expect(std::string(e.GetDescription()).find(corrupt) != std::string::npos,
                   "a corrupt file's refusal names it: " + std::string(e.GetDescription()));
      ++refused;
    }
  }
  std::cout << "  150 copies of " << what << ": " << read_ << " read, " << refused << " refused, none crashed"
            << std::endl;
  return ok;
}

/** Corrupt copies of the RTSTRUCT and the RTDOSE, anywhere and in the File Meta Information only, read as
 * RT objects and (the meta-corrupted ones, whose Modality cannot be found) through the generic image reader:
 * Debian's GDCM asserts on some malformed files (a truncated or overwritten meta group: before the structure
 * check, 1 in 10 such copies aborted the process), so the readers check the structure before GDCM sees it. */
bool
CheckCorruptFiles(const std::string & dir, const std::string & rtstruct, const std::string & rtdose)
{
  const auto   ct = itk::ReadBiomechanicalImage<CTImageType>(dir + "/ct.nrrd", "CT");
  std::mt19937 random(17);
  const auto   readStructure = [&](const std::string & path) { itk::ReadRTStructAsLabelImage(path, ct, OrganMap()); };
  const auto   readDose = [](const std::string & path) { itk::ReadDoseImage(path); };
  const auto readLabels = [](const std::string & path) { itk::ReadBiomechanicalImage<LabelImageType>(path, "labels"); };
  const std::size_t anywhere = std::numeric_limits<std::size_t>::max();
  bool              ok = CheckCorruptCopies(dir, rtstruct, "the RTSTRUCT", anywhere, readStructure, random);
  ok &= CheckCorruptCopies(dir, rtdose, "the RTDOSE", anywhere, readDose, random);
  const std::size_t structMeta = MetaInformationEnd(ReadFileBytes(rtstruct)) + 64;
  const std::size_t doseMeta = MetaInformationEnd(ReadFileBytes(rtdose)) + 64;
  ok &= CheckCorruptCopies(dir, rtstruct, "the RTSTRUCT (meta group)", structMeta, readStructure, random);
  ok &= CheckCorruptCopies(dir, rtstruct, "the RTSTRUCT as labels (meta group)", structMeta, readLabels, random);
  ok &= CheckCorruptCopies(dir, rtdose, "the RTDOSE (meta group)", doseMeta, readDose, random);
  return ok;
}

/** A CT series directory with one slice whose Transfer Syntax UID has an invalid VR (the single byte that made
 * GDCM's series scanner abort): refused naming the directory and the file. */
bool
CheckCorruptSeries(const std::string & dir, const std::string & rtstruct)
{
  const std::filesystem::path series = std::filesystem::path(dir) / "corrupt_series";
  std::filesystem::remove_all(series);
  std::filesystem::create_directories(series);
  std::string slice;
  for (const auto & entry : std::filesystem::directory_iterator(std::filesystem::path(rtstruct).parent_path()))
  {
    const std::string name = entry.path().filename().string();
    if (name.rfind("image", 0) == 0)
    {
      std::filesystem::copy_file(entry.path(), series / name);
      slice = slice.empty() || name < slice ? name : slice;
    }
  }
  const auto        intact = itk::ReadBiomechanicalImage<CTImageType>(series.string(), "CT");
  bool              ok = Expect(intact->GetLargestPossibleRegion().GetSize()[2] == Size[2], "the copied series reads");
  std::vector<char> bytes = ReadFileBytes((series / slice).string());
  std::size_t       pos = 132;
  while (pos + 8 <= bytes.size() &&
         !(bytes[pos] == 0x02 && bytes[pos + 1] == 0 && bytes[pos + 2] == 0x10 && bytes[pos + 3] == 0))
  {
    ++pos;
  }
  bytes[pos + 4] = 'J'; // (0002,0010) UI -> JI
  std::ofstream((series / slice).string(), std::ios::binary)
    .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ok &= Refuses("a CT series with a corrupt slice",
                [&] { itk::ReadBiomechanicalImage<CTImageType>(series.string(), "CT"); },
                { series.string(), slice, "corrupt", "(0002,0010)" });
  return ok;
}

} // namespace

int
itkDicomRTTest(int argc, char * argv[])
{
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "make" && argc == 3)
  {
    return MakeInputs(argv[2]);
  }
  if (mode == "masks" && argc >= 5)
  {
    return MakeMasks(argv[2], argv[3], std::vector<std::string>(argv + 4, argv + argc));
  }
  if (mode != "check" || argc != 5)
  {
    std::cerr << "usage: " << argv[0] << " make DIR | check DIR RTSTRUCT RTDOSE | masks LABELS DIR name=value..."
              << std::endl;
    return EXIT_FAILURE;
  }
  bool ok = true;
  try
  {
    ok &= CheckStructures(argv[2], argv[3]);
    ok &= CheckDose(argv[2], argv[4], argv[3]);
    ok &= CheckCorruptFiles(argv[2], argv[3], argv[4]);
    ok &= CheckCorruptSeries(argv[2], argv[3]);
  }
  catch (const std::exception & e)
  {
    std::cerr << "FAIL: unexpected exception: " << e.what() << std::endl;
    return EXIT_FAILURE;
  }
  std::cout << (ok ? "itkDicomRTTest passed" : "itkDicomRTTest FAILED") << std::endl;
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

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
#include "itkClinicalStructureSet.h"

#include "bmrError.h"
#include "bmrPhantom.h"
#include "itkConnectedComponentImageFilter.h"
#include "itkDicomRT.h"
#include "itkImageRegionConstIterator.h"
#include "itkImageIOFactory.h"
#include "itkImageRegionIterator.h"
#include "itkMetaDataObject.h"
#include "itkRelabelComponentImageFilter.h"

#include "itkDicomRTCommon.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace itk {

namespace {
constexpr const char * Where = "ReadClinicalPelvisAnatomy";
constexpr const char * NamesWhere = "ReadLabelNames";
const char * const     RequiredParts[] = { "prostate", "bladder", "rectum", "body" };

/** A name as the table compares it: lower case, without spaces, underscores and hyphens. */
std::string
NameKey(const std::string & name)
{
  std::string key;
  for (unsigned char c : name)
  {
    if (!std::isspace(c) && c != '_' && c != '-')
    {
      key += static_cast<char>(std::tolower(c));
    }
  }
  return key;
}

/** The part of a TG-263 name or synonym, or "" when the scene has none for it. */
std::string
PartOfName(const std::string & name)
{
  static const std::map<std::string, std::string> table = { { "prostate", "prostate" }, { "prostategland", "prostate" },
                                                            { "bladder", "bladder" },   { "urinarybladder", "bladder" },
                                                            { "rectum", "rectum" },     { "external", "body" },
                                                            { "body", "body" },         { "skin", "body" },
                                                            { "outline", "body" },      { "bodycontour", "body" },
                                                            { "femurheadl", "bone" },   { "femurheadr", "bone" },
                                                            { "femurl", "bone" },       { "femurr", "bone" },
                                                            { "femoralheadl", "bone" }, { "femoralheadr", "bone" },
                                                            { "femurneckl", "bone" },   { "femurneckr", "bone" },
                                                            { "bonepelvic", "bone" },   { "pelvis", "bone" },
                                                            { "pelvicbone", "bone" },   { "bones", "bone" },
                                                            { "bone", "bone" },         { "sacrum", "bone" },
                                                            { "coccyx", "bone" } };
  const auto                                      found = table.find(NameKey(name));
  return found == table.end() ? std::string() : found->second;
}

bool
IsFemoralHead(const std::string & roi)
{
  const std::string key = NameKey(roi);
  return key.rfind("femur", 0) == 0 || key.rfind("femoral", 0) == 0;
}

void
ApplyOverride(PelvisROIMapping &               mapping,
              const std::vector<std::string> & roiNames,
              const std::string &              roi,
              const std::string &              part,
              const std::string &              source)
{
  const auto named =
    std::find_if(roiNames.begin(), roiNames.end(), [&](const std::string & n) { return NameKey(n) == NameKey(roi); });
  if (named == roiNames.end())
  {
    bmr::FailInput(Where, source + ": the ROI map names \"" + roi + "\", which is not an ROI of the structure set");
  }
  const std::set<std::string> parts = { "prostate", "bladder", "rectum", "body", "bone", "ignore" };
  if (parts.count(part) == 0)
  {
    bmr::FailInput(Where,
                   source + ": the ROI map gives \"" + roi + "\" the part \"" + part +
                     "\" (known: prostate, bladder, rectum, body, bone, ignore)");
  }
  mapping.partOfROI.erase(*named);
  if (part != "ignore")
  {
    mapping.partOfROI[*named] = part;
  }
}

/** Fails unless each required part has exactly one ROI. */
void
CheckRequiredParts(const PelvisROIMapping & mapping, const std::string & source)
{
  for (const char * part : RequiredParts)
  {
    const auto rois = mapping.ROIsOf(part);
    if (rois.size() != 1)
    {
      const std::string found = rois.empty() ? "none" : "\"" + rois[0] + "\" and \"" + rois[1] + "\"";
      bmr::FailInput(Where,
                     source + ": the built-in pelvis scene needs one ROI for the " + part + " (TG-263 " +
                       (std::string(part) == "body" ? "External" : std::string(1, std::toupper(part[0])) + (part + 1)) +
                       ", or an override NAME=" + part + ", --roi-map on the command line); found " + found);
    }
  }
}

/** Fails when \a ct came from a DICOM series whose frame of reference the RTSTRUCT does not reference. */
void
CheckFrameOfReference(const std::string & rtstructPath, const Image<float, 3> * ct)
{
  std::string ctFrame;
  if (!ExposeMetaData<std::string>(ct->GetMetaDataDictionary(), "0020|0052", ctFrame))
  {
    return; // not a DICOM series: nothing to compare
  }
  const auto trim = [](std::string s) {
    s.erase(std::find(s.begin(), s.end(), '\0'), s.end());
    s.erase(s.find_last_not_of(' ') + 1);
    return s;
  };
  const auto frames = ReadRTStructFrameOfReferenceUIDs(rtstructPath);
  if (std::none_of(frames.begin(), frames.end(), [&](const std::string & f) { return trim(f) == trim(ctFrame); }))
  {
    bmr::FailInput(Where,
                   rtstructPath + ": its ROIs are in another frame of reference than the CT (" +
                     (frames.empty() ? std::string("none named") : trim(frames[0])) + " against the CT's " +
                     trim(ctFrame) + "): a structure set of another scan?");
  }
}

/** Marks as bone the soft-tissue voxels of \a labels at or above the threshold in \a ct, in pieces large enough. */
void
AddBoneFromCT(ClinicalAnatomy &               anatomy,
              const Image<float, 3> *         ct,
              const bmr::Scene &              scene,
              const ClinicalAnatomySettings & settings)
{
  using MaskType = Image<unsigned char, 3>;
  const std::int32_t tissue = scene.FindLabel("soft_tissue")->value;
  const std::int32_t bone = scene.FindLabel("bone")->value;
  auto               mask = MaskType::New();
  mask->CopyInformation(anatomy.labels);
  mask->SetRegions(anatomy.labels->GetLargestPossibleRegion());
  mask->Allocate();
  ImageRegionConstIterator<Image<std::int32_t, 3>> label(anatomy.labels, anatomy.labels->GetLargestPossibleRegion());
  ImageRegionConstIterator<Image<float, 3>>        hu(ct, anatomy.labels->GetLargestPossibleRegion());
  ImageRegionIterator<MaskType>                    m(mask, mask->GetLargestPossibleRegion());
  for (; !m.IsAtEnd(); ++m, ++label, ++hu)
  {
    m.Set(label.Get() == tissue && hu.Get() >= settings.boneThresholdHU ? 1 : 0);
  }
  auto components = ConnectedComponentImageFilter<MaskType, Image<std::int32_t, 3>>::New();
  components->SetInput(mask);
  components->FullyConnectedOn();
  auto         relabel = RelabelComponentImageFilter<Image<std::int32_t, 3>, Image<std::int32_t, 3>>::New();
  const auto & spacing = ct->GetSpacing();
  const double voxelCC = spacing[0] * spacing[1] * spacing[2] / 1000.0;
  relabel->SetInput(components->GetOutput());
  relabel->SetMinimumObjectSize(static_cast<SizeValueType>(std::ceil(settings.minimumBoneVolumeCC / voxelCC)));
  relabel->Update();
  anatomy.bonePiecesDropped = relabel->GetOriginalNumberOfObjects() - relabel->GetNumberOfObjects();
  ImageRegionConstIterator<Image<std::int32_t, 3>> piece(relabel->GetOutput(), mask->GetLargestPossibleRegion());
  ImageRegionIterator<Image<std::int32_t, 3>>      out(anatomy.labels, anatomy.labels->GetLargestPossibleRegion());
  for (; !out.IsAtEnd(); ++out, ++piece)
  {
    if (piece.Get() > 0)
    {
      out.Set(bone);
    }
  }
  anatomy.boneFromCT = true;
}
/** Bone from the CT unless a bone ROI other than a femoral head exists; then the bone voxels counted. */
void
FinishBone(ClinicalAnatomy &               anatomy,
           const Image<float, 3> *         ct,
           const bmr::Scene &              scene,
           const ClinicalAnatomySettings & settings)
{
  const auto bones = anatomy.mapping.ROIsOf("bone");
  if (std::all_of(bones.begin(), bones.end(), IsFemoralHead))
  {
    AddBoneFromCT(anatomy, ct, scene, settings);
  }
  const std::int32_t bone = scene.FindLabel("bone")->value;
  const auto *       buffer = anatomy.labels->GetBufferPointer();
  anatomy.boneVoxels =
    std::count(buffer, buffer + anatomy.labels->GetLargestPossibleRegion().GetNumberOfPixels(), bone);
}

/** Fails unless the label map and the CT share one grid (the bone is thresholded voxel by voxel). */
void
CheckSameGrid(const ImageBase<3> * labels, const ImageBase<3> * ct, const std::string & source)
{
  const bool same =
    labels->GetLargestPossibleRegion() == ct->GetLargestPossibleRegion() &&
    labels->GetOrigin().EuclideanDistanceTo(ct->GetOrigin()) <= 1e-3 &&
    (labels->GetSpacing() - ct->GetSpacing()).GetNorm() <= 1e-4 &&
    (labels->GetDirection().GetVnlMatrix() - ct->GetDirection().GetVnlMatrix()).absolute_value_max() <= 1e-4;
  if (!same)
  {
    bmr::FailInput(Where, source + ": the label map is not on the grid of its CT (size, origin, spacing, direction)");
  }
}

/** The scene's labels from a named label map: each named value as its part (the body as soft tissue), the values
 * of left-out names as soft tissue (a label map's labelled voxels lie inside the patient), 0 as air; fails on a
 * value without a name and on a required part without voxels. */
Image<std::int32_t, 3>::Pointer
SceneLabelsOf(const Image<std::int32_t, 3> *              labels,
              const std::map<std::int32_t, std::string> & names,
              const PelvisROIMapping &                    mapping,
              const bmr::Scene &                          scene,
              const std::string &                         source)
{
  const std::int32_t                   tissue = scene.FindLabel("soft_tissue")->value;
  std::map<std::int32_t, std::int32_t> sceneValue{ { 0, scene.FindLabel("air")->value } };
  for (const auto & [value, name] : names)
  {
    const auto part = mapping.partOfROI.find(name);
    if (value != 0)
    {
      sceneValue[value] =
        part == mapping.partOfROI.end() || part->second == "body" ? tissue : scene.FindLabel(part->second)->value;
    }
  }
  auto out = Image<std::int32_t, 3>::New();
  out->CopyInformation(labels);
  out->SetRegions(labels->GetLargestPossibleRegion());
  out->Allocate();
  std::map<std::int32_t, std::size_t>              voxels;
  ImageRegionConstIterator<Image<std::int32_t, 3>> in(labels, labels->GetLargestPossibleRegion());
  ImageRegionIterator<Image<std::int32_t, 3>>      o(out, out->GetLargestPossibleRegion());
  for (; !in.IsAtEnd(); ++in, ++o)
  {
    const auto found = sceneValue.find(in.Get());
    if (found == sceneValue.end())
    {
      bmr::FailInput(Where, source + ": label value " + std::to_string(in.Get()) + " has no name in the names table");
    }
    o.Set(found->second);
    ++voxels[in.Get()];
  }
  for (const char * part : RequiredParts)
  {
    const std::string roi = mapping.ROIsOf(part).front();
    const auto        named = std::find_if(names.begin(), names.end(), [&](const auto & n) { return n.second == roi; });
    if (voxels[named->first] == 0)
    {
      bmr::FailInput(Where,
                     source + ": \"" + roi + "\" (label value " + std::to_string(named->first) + ", the " + part +
                       ") holds no voxel");
    }
  }
  return out;
}
/** A names table: "value,name" (CSV, an optional header line) or "value name ..." (a 3D Slicer color table)
 * per line, '#' comments. */
std::map<std::int32_t, std::string>
NamesTable(const std::string & path)
{
  std::ifstream in(path);
  if (!in)
  {
    bmr::FailInput(NamesWhere, "cannot read the label names table \"" + path + "\"");
  }
  std::map<std::int32_t, std::string> names;
  std::size_t                         number = 0;
  for (std::string line; std::getline(in, line);)
  {
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#')
    {
      continue;
    }
    const bool         csv = line.find(',') != std::string::npos;
    std::istringstream fields(line);
    std::string        value, name;
    if (csv)
    {
      std::getline(fields >> std::ws, value, ',');
      std::getline(fields, name, ',');
    }
    else
    {
      fields >> value >> name;
    }
    name = dicomrt::Trim(name);
    char *     end = nullptr;
    const long v = std::strtol(value.c_str(), &end, 10);
    if (end == value.c_str() || *end != '\0' || name.empty())
    {
      if (names.empty() && end == value.c_str())
      {
        continue; // a header line ("value,name")
      }
      bmr::FailInput(NamesWhere,
                     path + ", line " + std::to_string(number) + ": expected \"VALUE,NAME\" or \"VALUE NAME ...\"");
    }
    if (!names.emplace(static_cast<std::int32_t>(v), name).second)
    {
      bmr::FailInput(NamesWhere, path + ", line " + std::to_string(number) + ": value " + value + " named twice");
    }
  }
  return names;
}

/** The segment names of a 3D Slicer segmentation's header (Segment<i>_Name, _LabelValue, _Layer); empty when the
 * file has none. */
std::map<std::int32_t, std::string>
SegmentationNames(ImageIOBase * io, const std::string & path)
{
  const MetaDataDictionary &          header = io->GetMetaDataDictionary();
  std::map<std::int32_t, std::string> names;
  for (unsigned int i = 0;; ++i)
  {
    const std::string key = "Segment" + std::to_string(i) + "_";
    std::string       name, value, layer = "0";
    if (!ExposeMetaData<std::string>(header, key + "Name", name))
    {
      return names;
    }
    ExposeMetaData<std::string>(header, key + "Layer", layer);
    if (!ExposeMetaData<std::string>(header, key + "LabelValue", value) || dicomrt::Trim(layer) != "0")
    {
      bmr::FailInput(NamesWhere,
                     path + ": segment \"" + name + "\" has no label value or lies in another layer " +
                       "(overlapping segments: export them from Slicer as one label map)");
    }
    char *     end = nullptr;
    const long v = std::strtol(value.c_str(), &end, 10);
    if (end == value.c_str())
    {
      bmr::FailInput(NamesWhere, path + ": segment \"" + name + "\" has the label value \"" + value + "\"");
    }
    names[static_cast<std::int32_t>(v)] = dicomrt::Trim(name);
  }
}
} // namespace

std::map<std::int32_t, std::string>
ReadLabelNames(const std::string & path)
{
  const ImageIOBase::Pointer io = ImageIOFactory::CreateImageIO(path.c_str(), ImageIOFactory::IOFileModeEnum::ReadMode);
  if (io)
  {
    io->SetFileName(path);
    io->ReadImageInformation();
    return SegmentationNames(io, path);
  }
  return NamesTable(path);
}

std::vector<std::string>
PelvisROIMapping::ROIsOf(const std::string & part) const
{
  std::vector<std::string> rois;
  for (const auto & [roi, p] : this->partOfROI)
  {
    if (p == part)
    {
      rois.push_back(roi);
    }
  }
  return rois;
}

PelvisROIMapping
MapPelvisROIs(const std::vector<std::string> &           roiNames,
              const std::map<std::string, std::string> & overrides,
              const std::string &                        source)
{
  PelvisROIMapping mapping;
  for (const auto & roi : roiNames)
  {
    const std::string part = PartOfName(roi);
    if (!part.empty())
    {
      mapping.partOfROI[roi] = part;
    }
  }
  for (const auto & [roi, part] : overrides)
  {
    ApplyOverride(mapping, roiNames, roi, part, source);
  }
  for (const auto & roi : roiNames)
  {
    if (mapping.partOfROI.count(roi) == 0)
    {
      mapping.leftOut.push_back(roi);
    }
  }
  CheckRequiredParts(mapping, source);
  return mapping;
}

bmr::Scene
BuiltInPelvisScene()
{
  bmr::Scene scene = bmr::PelvisPhantomScene(50.0, true);
  scene.name = "pelvis (built-in)";
  return scene;
}

ClinicalAnatomy
ReadClinicalPelvisAnatomy(const std::string &                        rtstructPath,
                          const Image<float, 3> *                    ct,
                          const std::map<std::string, std::string> & overrides,
                          const ClinicalAnatomySettings &            settings)
{
  if (ct == nullptr)
  {
    bmr::FailInput(Where, rtstructPath + ": no CT given to grid the structure set on");
  }
  ClinicalAnatomy  anatomy;
  const bmr::Scene scene = BuiltInPelvisScene();
  anatomy.mapping = MapPelvisROIs(ReadRTStructROINames(rtstructPath), overrides, rtstructPath);
  CheckFrameOfReference(rtstructPath, ct);
  std::map<std::string, std::int32_t> labelOfROI;
  for (const auto & [roi, part] : anatomy.mapping.partOfROI)
  {
    labelOfROI[roi] = scene.FindLabel(part == "body" ? "soft_tissue" : part)->value;
  }
  RTStructRasterizationOptions options;
  options.ignoreUnmappedROIs = true;
  options.backgroundLabel = scene.FindLabel("air")->value;
  anatomy.labels = ReadRTStructAsLabelImage(rtstructPath, ct, labelOfROI, options);
  FinishBone(anatomy, ct, scene, settings);
  return anatomy;
}

ClinicalAnatomy
ClinicalPelvisAnatomyFromLabelMap(const Image<std::int32_t, 3> *              labels,
                                  const std::map<std::int32_t, std::string> & names,
                                  const Image<float, 3> *                     ct,
                                  const std::map<std::string, std::string> &  overrides,
                                  const ClinicalAnatomySettings &             settings,
                                  const std::string &                         source)
{
  if (labels == nullptr || ct == nullptr)
  {
    bmr::FailInput(Where, source + ": no label map or no CT");
  }
  CheckSameGrid(labels, ct, source);
  std::vector<std::string> named;
  for (const auto & [value, name] : names)
  {
    if (value != 0)
    {
      named.push_back(name);
    }
  }
  ClinicalAnatomy  anatomy;
  const bmr::Scene scene = BuiltInPelvisScene();
  anatomy.mapping = MapPelvisROIs(named, overrides, source);
  anatomy.labels = SceneLabelsOf(labels, names, anatomy.mapping, scene, source);
  FinishBone(anatomy, ct, scene, settings);
  return anatomy;
}

} // namespace itk

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
// register's anatomy: a scene file with label maps (or RTSTRUCTs named as its labels), or, without a scene, two
// clinical structure sets registered with the built-in pelvis scene (itkClinicalStructureSet.h).
#include "biomechregCommon.h"
#include "itkClinicalStructureSet.h"
#include "itkDicomRT.h"

#include <nlohmann/json.hpp>

#include <sstream>

namespace bmrcli {

namespace {
/** --roi-map Prostate_CTV=prostate,Couch=ignore: ROI name -> part of the built-in scene. */
std::map<std::string, std::string>
ParseROIMap(const std::string & list)
{
  std::map<std::string, std::string> overrides;
  std::stringstream                  items(list);
  for (std::string item; std::getline(items, item, ',');)
  {
    const auto equals = item.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == item.size())
    {
      throw UsageError("--roi-map takes ROI=PART pairs separated by commas (PART: prostate, bladder, rectum, body, "
                       "bone, ignore), got \"" +
                       item + "\"");
    }
    overrides[item.substr(0, equals)] = item.substr(equals + 1);
  }
  return overrides;
}

/** One line: which ROI became which part, where the bone came from, what was left out. */
std::string
MappingText(const itk::ClinicalAnatomy & anatomy, const itk::ClinicalAnatomySettings & settings)
{
  std::ostringstream text;
  const char *       separator = "";
  for (const auto & [roi, part] : anatomy.mapping.partOfROI)
  {
    text << separator << roi << " -> " << (part == "body" ? "body (soft tissue)" : part);
    separator = ", ";
  }
  if (anatomy.boneFromCT)
  {
    text << "; bone from the CT (>= " << settings.boneThresholdHU
         << " HU inside the body, pieces >= " << settings.minimumBoneVolumeCC << " cc): " << anatomy.boneVoxels
         << " voxels";
  }
  text << "; left out: " << (anatomy.mapping.leftOut.empty() ? "none" : "");
  for (std::size_t i = 0; i < anatomy.mapping.leftOut.size(); ++i)
  {
    text << (i ? ", " : "") << anatomy.mapping.leftOut[i];
  }
  return text.str();
}

nlohmann::json
MappingJson(const itk::ClinicalAnatomy & anatomy, const std::string & source, bool rtstruct)
{
  return { { rtstruct ? "rtstruct" : "label_map", source }, { "part_of_roi", anatomy.mapping.partOfROI },
           { "left_out", anatomy.mapping.leftOut },         { "bone_from_ct", anatomy.boneFromCT },
           { "bone_voxels", anatomy.boneVoxels },           { "bone_pieces_dropped", anatomy.bonePiecesDropped } };
}

bool
IsRTStruct(const std::string & path)
{
  return itk::ReadDicomModality(path) == "RTSTRUCT";
}

/** One scan's anatomy with the built-in scene: from its RTSTRUCT, or from its label map and the label names (a
 * names table, or the segment names of a Slicer segmentation). */
itk::ClinicalAnatomy
ScanAnatomy(const std::string &                        labelsPath,
            const std::string &                        namesPath,
            const CTImageType *                        ct,
            const std::map<std::string, std::string> & overrides,
            const itk::ClinicalAnatomySettings &       settings,
            const char *                               what)
{
  if (IsRTStruct(labelsPath))
  {
    return itk::ReadClinicalPelvisAnatomy(labelsPath, ct, overrides, settings);
  }
  const auto names = itk::ReadLabelNames(namesPath.empty() ? labelsPath : namesPath);
  if (names.empty())
  {
    throw UsageError(std::string("--scene is required unless both label inputs are RTSTRUCTs or named label maps (a "
                                 "Slicer .seg.nrrd, or --moving-label-names/--fixed-label-names FILE); ") +
                     what + " \"" + labelsPath + "\" is neither");
  }
  const auto labels = ReadImage<LabelImageType>(labelsPath, "label image");
  return itk::ClinicalPelvisAnatomyFromLabelMap(labels, names, ct, overrides, settings, labelsPath);
}

/** Both scans' anatomy from their structure sets or named label maps, with the built-in scene; the mapping printed
 * and written. */
RegistrationAnatomy
ReadStructureSets(const RegistrationPaths & paths, const CTImageType * movingCT, const CTImageType * fixedCT)
{
  const auto                         overrides = ParseROIMap(paths.roiMap);
  const itk::ClinicalAnatomySettings settings;
  const auto                         moving =
    ScanAnatomy(paths.movingLabels, paths.movingLabelNames, movingCT, overrides, settings, "--moving-labels");
  const auto fixed =
    ScanAnatomy(paths.fixedLabels, paths.fixedLabelNames, fixedCT, overrides, settings, "--fixed-labels");
  PrintLine("  built-in pelvis scene; moving structure set: " + MappingText(moving, settings));
  PrintLine("  fixed structure set: " + MappingText(fixed, settings));
  MakeOutputDirectory(paths.out);
  const nlohmann::json report = { { "scene", "pelvis (built-in)" },
                                  { "bone_threshold_HU", settings.boneThresholdHU },
                                  { "minimum_bone_volume_cc", settings.minimumBoneVolumeCC },
                                  { "moving", MappingJson(moving, paths.movingLabels, IsRTStruct(paths.movingLabels)) },
                                  { "fixed", MappingJson(fixed, paths.fixedLabels, IsRTStruct(paths.fixedLabels)) } };
  bmr::WriteTextFileAtomically(paths.out + "/structure_set.json", report.dump(2) + "\n");
  itk::WriteImageAtomically(moving.labels.GetPointer(), paths.out + "/moving_labels_from_rois.nrrd", 1);
  itk::WriteImageAtomically(fixed.labels.GetPointer(), paths.out + "/fixed_labels_from_rois.nrrd", 1);
  RegistrationAnatomy anatomy{ itk::BuiltInPelvisScene(), moving.labels, fixed.labels, {} };
  for (const char * organ : { "prostate", "bladder", "rectum" })
  {
    anatomy.fixedROIOfOrgan[organ] = fixed.mapping.ROIsOf(organ).front();
  }
  return anatomy;
}
} // namespace

RegistrationAnatomy
ReadRegistrationAnatomy(const RegistrationPaths & paths,
                        const CTImageType *       movingCT,
                        const CTImageType *       fixedCT,
                        bool                      ignoreROIs)
{
  if (paths.scene.empty())
  {
    return ReadStructureSets(paths, movingCT, fixedCT);
  }
  if (!paths.roiMap.empty() || !paths.movingLabelNames.empty() || !paths.fixedLabelNames.empty())
  {
    throw UsageError("--roi-map and --moving/fixed-label-names apply to the built-in pelvis scene only (without "
                     "--scene)");
  }
  RegistrationAnatomy anatomy;
  anatomy.scene = bmr::ReadScene(paths.scene);
  anatomy.movingLabels =
    ReadLabelsOrRTStruct(paths.movingLabels, "moving label image", movingCT, anatomy.scene, ignoreROIs);
  anatomy.fixedLabels =
    ReadLabelsOrRTStruct(paths.fixedLabels, "fixed label image", fixedCT, anatomy.scene, ignoreROIs);
  return anatomy;
}

} // namespace bmrcli

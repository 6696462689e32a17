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
#ifndef itkClinicalStructureSet_h
#define itkClinicalStructureSet_h

#include "BiomechanicalRegistrationExport.h"
#include "bmrScene.h"
#include "itkImage.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace itk {

// A planning system's structure set as the built-in pelvis scene's anatomy (Doxygen group
// BiomechanicalRegistrationDicomRT): no scene file, no drawn tissue or bone.

/** \brief Which ROI of a structure set plays which part of the built-in pelvis scene.
 *
 * Parts: "prostate", "bladder", "rectum", "body" (the patient's outline: the surrounding tissue is the body less
 * the organs and the bone), "bone" (any number: femoral heads, pelvic bones). ROIs with no part are left out.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
struct BiomechanicalRegistration_EXPORT PelvisROIMapping
{
  std::map<std::string, std::string> partOfROI; ///< ROI name as in the file -> part
  std::vector<std::string>           leftOut;   ///< the file's other ROIs (PTVs, bowel, couch, ...)
  /** The ROIs of \a part, in the order of their names. */
  std::vector<std::string>
  ROIsOf(const std::string & part) const;
};

/** \brief Maps \a roiNames to the pelvis scene's parts by their TG-263 names and documented synonyms, matched
 * case-insensitively and ignoring spaces, underscores and hyphens:
 * - prostate: Prostate, ProstateGland (a CTV or PTV, a margin around it, is left out);
 * - bladder: Bladder, UrinaryBladder; rectum: Rectum;
 * - body: External, Body, Skin, Outline, BodyContour;
 * - bone: Femur_Head_L/R, Femur_L/R, FemoralHead_L/R, Femur_Neck_L/R, Bone_Pelvic, Pelvis, PelvicBone, Bones,
 *   Bone, Sacrum, Coccyx.
 * \a overrides (ROI name -> part or "ignore") win over the table. Fails (itk::InvalidArgumentError, one line naming
 * \a source and the part) when the prostate, bladder, rectum or body has no ROI or more than one, or an override
 * names an ROI the file lacks or an unknown part. \ingroup BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT PelvisROIMapping
MapPelvisROIs(const std::vector<std::string> &           roiNames,
              const std::map<std::string, std::string> & overrides,
              const std::string &                        source);

/** How bone is found in the CT when the structure set has no pelvic bone ROI. */
struct BiomechanicalRegistration_EXPORT ClinicalAnatomySettings
{
  /** HU at and above which a voxel of the surrounding tissue is bone: above soft tissue (about 40 HU) and fat,
   * below cancellous bone (200-400 HU), so that the boundary lies near the partial-volume midpoint of cortical
   * bone. */
  double boneThresholdHU{ 250.0 };
  /** Connected pieces of bone smaller than this [cc] are left as tissue: calcifications, fiducial markers,
   * implanted seeds (inside the prostate they are prostate anyway), noise. */
  double minimumBoneVolumeCC{ 1.0 };
};

/** The built-in pelvis scene's labels of one scan, and where they came from. */
struct BiomechanicalRegistration_EXPORT ClinicalAnatomy
{
  Image<std::int32_t, 3>::Pointer labels; ///< on the CT's grid, the values of BuiltInPelvisScene()
  PelvisROIMapping                mapping;
  bool                            boneFromCT{ false }; ///< the bone was thresholded from the CT
  std::size_t                     boneVoxels{ 0 };
  std::size_t                     bonePiecesDropped{ 0 }; ///< pieces under minimumBoneVolumeCC
};

/** The scene a structure set is registered with when none is given: the pelvis phantoms' estimation scene
 * (air, soft tissue 10 kPa, the prostate's modulus unknown in 20-600 kPa, bladder and rectum hollow and loaded,
 * bone fixed), the scene whose stated intervals were calibrated. \ingroup BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT bmr::Scene
                                 BuiltInPelvisScene();

/** \brief The built-in pelvis scene's label map of a scan from its RTSTRUCT \a rtstructPath drawn on \a ct.
 *
 * The ROIs are mapped (MapPelvisROIs()) and rasterized (ReadRTStructAsLabelImage(): where ROIs overlap the smaller
 * wins, so an organ inside the body keeps its label): the body becomes soft tissue, outside it air, the organs and
 * bone ROIs their labels. Unless an ROI other than a femoral head is bone, bone is also taken from the CT: voxels
 * of the soft tissue at or above ClinicalAnatomySettings::boneThresholdHU, in connected pieces (26-connected) of
 * at least minimumBoneVolumeCC. Fails (itk::InvalidArgumentError, one line naming the file) as MapPelvisROIs()
 * does, when the RTSTRUCT's frame of reference is not the CT's (when the CT is a DICOM series and says), or as
 * ReadRTStructAsLabelImage() does. \ingroup BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT ClinicalAnatomy
ReadClinicalPelvisAnatomy(const std::string &                        rtstructPath,
                          const Image<float, 3> *                    ct,
                          const std::map<std::string, std::string> & overrides = {},
                          const ClinicalAnatomySettings &            settings = ClinicalAnatomySettings());

/** \brief A label map's names by label value: a 3D Slicer segmentation's (.seg.nrrd: Segment<i>_Name and
 * Segment<i>_LabelValue in its header; an empty map when the image has none), or a names table: one "value,name"
 * per line (a CSV, an optional header line) or "value name r g b a" (a 3D Slicer color table), '#' comments.
 * Throws itk::InvalidArgumentError naming the file and line for a malformed line or a value named twice, and for a
 * segmentation whose segments lie in several layers (overlapping segments). \ingroup BiomechanicalRegistrationDicomRT
 */
BiomechanicalRegistration_EXPORT std::map<std::int32_t, std::string>
                                 ReadLabelNames(const std::string & path);

/** \brief The built-in pelvis scene's label map of a scan from a label map whose values are named (\a names:
 * ReadLabelNames()), drawn on \a ct (same grid).
 *
 * The names are mapped as an RTSTRUCT's ROIs (MapPelvisROIs(), \a overrides as there); each voxel takes its name's
 * part, the body as soft tissue. A label map holds one value per voxel, so its labelled voxels all lie inside the
 * patient: those of names the scene does not use (PTVs, bowel, seminal vesicles, "ignore" overrides) become soft
 * tissue, and value 0 is air whatever its name. Bone comes from the CT as for ReadClinicalPelvisAnatomy(). Fails
 * (itk::InvalidArgumentError, one line naming \a source) as MapPelvisROIs() does, on a value of the map without a
 * name, a required part (prostate, bladder, rectum, body) without voxels, or a CT on another grid.
 * \ingroup BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT ClinicalAnatomy
ClinicalPelvisAnatomyFromLabelMap(const Image<std::int32_t, 3> *              labels,
                                  const std::map<std::int32_t, std::string> & names,
                                  const Image<float, 3> *                     ct,
                                  const std::map<std::string, std::string> &  overrides = {},
                                  const ClinicalAnatomySettings &             settings = ClinicalAnatomySettings(),
                                  const std::string &                         source = "label map");

} // namespace itk

#endif

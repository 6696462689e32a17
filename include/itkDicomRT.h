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
#ifndef itkDicomRT_h
#define itkDicomRT_h

#include "BiomechanicalRegistrationExport.h"
#include "bmrScene.h"
#include "itkImage.h"
#include "itkVector.h"
#include "itkPlanarContourFractions.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace itk {

/** Label map made from an RTSTRUCT: one label value per ROI, 0 (or the chosen background) elsewhere.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
using DicomRTLabelImageType = Image<std::int32_t, 3>;
/** Dose grid [Gy]. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT
 */
using DicomRTDoseImageType = Image<float, 3>;
/** Displacement field [mm, LPS] (the pipelines' BiomechanicalFieldType). \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationDicomRT */
using DicomRTDisplacementFieldType = Image<Vector<double, 3>, 3>;

/** A deformable registration read from DICOM (ReadDeformableSpatialRegistration()).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
struct BiomechanicalRegistration_EXPORT DicomDeformableRegistration
{
  /** At each grid point x of the registered frame (the fixed scan's), the displacement u [mm] to the point
   * x + u of the source frame (the moving scan's): a pull-back field, as itk::ImageWarper takes. */
  DicomRTDisplacementFieldType::Pointer field;
  std::string                           registeredFrameOfReferenceUID; ///< the object's own (0020,0052)
  std::string                           sourceFrameOfReferenceUID;     ///< (0064,0003)
};

/** \brief Reads a DICOM Deformable Spatial Registration object (SOP class 1.2.840.10008.5.1.4.1.1.66.3) with one
 * registration and one deformation grid, as written by WriteDeformableSpatialRegistration(), SlicerRT or
 * plastimatch.
 *
 * PS3.3 C.20.3.1.1: a registered point x maps to the source point M_post(M_pre x + D(x)); here both matrices
 * must be absent or the identity, so the grid's vectors D are the field itself. The grid: Image Position and
 * Orientation (Patient), the third axis the row x column normal, Grid Resolution as spacing, Vector Grid Data
 * (32-bit floats, x fastest) as the vectors. Throws an itk::ExceptionObject naming \a path in one line when the
 * file is not DICOM or not that SOP class, holds several registrations or grids, has a matrix other than the
 * identity, or a grid attribute is missing or of the wrong length. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT DicomDeformableRegistration
ReadDeformableSpatialRegistration(const std::string & path);

/** \brief The DICOM Modality (0008,0060) of \a path, without its padding ("RTSTRUCT", "RTDOSE", "CT", ...).
 *
 * A cheap check that reads only the file's header up to the Modality: returns an empty string, without
 * throwing, when \a path is not a DICOM Part 10 file (no "DICM" after the 128-byte preamble), is a directory,
 * cannot be opened, or has no Modality. Used to tell an RTSTRUCT or RTDOSE from any other image file.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::string
                                 ReadDicomModality(const std::string & path);

/** \brief The ROI names of an RTSTRUCT, in the order of its Structure Set ROI Sequence (3006,0020), with the
 * DICOM padding (trailing spaces) removed.
 *
 * Throws an itk::ExceptionObject naming \a path when the file cannot be read as DICOM or its Modality is not
 * RTSTRUCT. A command line maps these names to a scene's labels.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::vector<std::string>
                                 ReadRTStructROINames(const std::string & rtstructPath);

/** \brief The Frame of Reference UIDs (0020,0052) an RTSTRUCT's Referenced Frame of Reference Sequence (3006,0010)
 * names: the patient coordinate systems its contours are in. Throws as ReadRTStructROINames().
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::vector<std::string>
                                 ReadRTStructFrameOfReferenceUIDs(const std::string & rtstructPath);

/** How ReadRTStructAsLabelImage() treats what the map does not cover.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
struct BiomechanicalRegistration_EXPORT RTStructRasterizationOptions
{
  /** false (default): an ROI of the file whose name is not in the map is an error; true: it is skipped
   * (couch, body outline, planning volumes of a clinical structure set). */
  bool ignoreUnmappedROIs{ false };
  /** Value of the voxels that no mapped ROI covers. */
  std::int32_t backgroundLabel{ 0 };
};

/** \brief Rasterizes the closed planar contours of an RTSTRUCT onto \a referenceGrid (the CT the structures
 * were drawn on): a label map with the grid's size, spacing [mm], origin [mm] and direction (its largest
 * possible region, index 0-based).
 *
 * \param rtstructPath   an RTSTRUCT file (Modality RTSTRUCT); contour points are patient LPS [mm].
 * \param referenceGrid  the grid of the output; only its geometry is used.
 * \param roiNameToLabel label value of each ROI name. Names match case-insensitively and ignoring
 *                       surrounding whitespace ("Prostate " matches "prostate").
 * \param options        unmapped ROIs and the background value.
 *
 * Each contour (ContourGeometricType CLOSED_PLANAR) is assigned to the slice of the grid whose centre it lies
 * on: every point's continuous slice index k must be within half a slice (0.5) of one integer k0 in the
 * grid. Within that slice, a voxel centre belongs to the ROI when a ray from it crosses the ROI's contours of
 * that slice an odd number of times (even-odd rule), so holes (an inner contour, or a keyhole) and several
 * contours per slice are handled. The test is done in the grid's continuous index space, so any direction
 * matrix whose third axis is the contours' normal works.
 *
 * Overlapping ROIs: a voxel covered by several mapped ROIs gets the label of the ROI with the fewest voxels
 * (the most specific structure: an organ inside a body outline keeps the organ's label whatever the order
 * of the file); ties go to the ROI that comes first in the file.
 *
 * Throws an itk::ExceptionObject, in one line naming \a rtstructPath (and the ROI where one is at fault),
 * when: the file is not DICOM, is truncated or corrupt, or its Modality is not RTSTRUCT; it has no
 * Referenced Frame of Reference Sequence (3006,0010) or no referenced series in it; an ROI name is not in the
 * map (unless options.ignoreUnmappedROIs) or a name of the map is not in the file; two ROIs or two map
 * entries have the same name; a mapped ROI has no contour or a contour that is not CLOSED_PLANAR, has fewer
 * than 3 points, holds a number of coordinates other than 3 x Number of Contour Points, or a non-finite one;
 * a contour matches no slice of the grid or lies outside it in-plane (beyond half a voxel of its border).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT DicomRTLabelImageType::Pointer
                                 ReadRTStructAsLabelImage(const std::string &                         rtstructPath,
                                                          const ImageBase<3> *                        referenceGrid,
                                                          const std::map<std::string, std::int32_t> & roiNameToLabel,
                                                          const RTStructRasterizationOptions &        options = {});

/** \brief The area fraction of each voxel of \a referenceGrid that each ROI of \a roiNames encloses in an RTSTRUCT:
 * PlanarContourAreaFractions() of the ROI's contours, one image per name (names as given, matched as
 * ReadRTStructAsLabelImage() matches them; other ROIs of the file are skipped).
 *
 * Where ReadRTStructAsLabelImage() keeps one bit per voxel, these keep where the polygon runs inside it: the input
 * of ComputeProbabilityDistanceMap() for a fixed organ drawn as contours (RegisterSegmentedPair()'s fixed
 * probabilities). Overlaps are not resolved: each ROI's own region. Throws itk::ExceptionObject as
 * ReadRTStructAsLabelImage() does, naming the file and the ROI, and when a name is not an ROI of the file.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::map<std::string, ContourFractionImageType::Pointer>
                                 ReadRTStructAreaFractions(const std::string &              rtstructPath,
                                                           const ImageBase<3> *             referenceGrid,
                                                           const std::vector<std::string> & roiNames);

/** \brief Reads a DICOM RTDOSE as a dose image [Gy] on the dose grid.
 *
 * The grid: Image Position (Patient) (0020,0032) is the origin [LPS mm], Image Orientation (Patient)
 * (0020,0037) the row and column directions (the slice direction their cross product), Pixel Spacing
 * (0028,0030) the in-plane spacing [mm] (row spacing, then column spacing), and the Grid Frame Offset Vector
 * (3004,000C) the frames' positions along the slice direction [mm]: relative to the origin when its first
 * value is 0, otherwise (allowed only for the axial orientation 1\0\0\0\1\0) their z coordinates. The
 * offsets must be evenly spaced (every step within 0.1 % of the mean step or 0.001 mm, whichever is larger);
 * decreasing offsets give a direction whose slice axis points against the normal. A single frame gets a
 * slice spacing of 1 mm.
 * Values: stored value (unsigned or signed integers of 16 or 32 bits) x Dose Grid Scaling (3004,000E).
 *
 * Throws an itk::ExceptionObject, in one line naming \a path, when the file is not DICOM, is truncated or
 * corrupt, its Modality is not RTDOSE, the Dose Units (3004,0002) are not GY (RELATIVE is refused: no
 * absolute dose), a geometry tag is missing or malformed, the offsets are not evenly spaced, the pixels are
 * not one sample of 16 or 32 bits, or the pixel data hold fewer values than Rows x Columns x Number of
 * Frames. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT DicomRTDoseImageType::Pointer
                                 ReadRTDose(const std::string & path);

/** \brief A dose image [Gy] from an RTDOSE file (ReadRTDose()) when ReadDicomModality(\a path) is RTDOSE,
 * otherwise from any 3-D image ITK reads (or a DICOM series directory), whose values are taken as Gy
 * (itk::ReadBiomechanicalImage(): non-finite values and bad geometry are refused).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT DicomRTDoseImageType::Pointer
                                 ReadDoseImage(const std::string & path);

/** \brief The ROI name of every structure of \a scene by label value: each label's name, the labels with the role
 * outside (air, background) left out. The map ReadRTStructAsLabelImage() (inverted) and WriteRTStruct() take when
 * the ROIs are named as the scene's labels, as on the command line.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::map<std::int32_t, std::string>
                                 SceneROINames(const bmr::Scene & scene);

} // namespace itk

#endif

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
#ifndef itkDicomRTWriters_h
#define itkDicomRTWriters_h

#include "itkDicomRT.h"

#include <cstdint>
#include <map>
#include <string>

namespace itk {

/** \brief Writes a label map as a DICOM RT Structure Set that references a CT series.
 *
 * One ROI per entry of \a roiNames (label value -> ROI name) that holds voxels of \a labels, numbered from 1
 * in the map's order. Each slice of the label map contributes the closed planar contours of that label's
 * voxels: the 0.5 level of its indicator, traced by marching squares (itk::ContourExtractor2DImageFilter) on
 * the slice padded by one voxel of background, so every contour closes and runs half a voxel outside the
 * outermost voxel centres, holes included as inner contours; collinear vertices are dropped. Rasterizing the
 * contours again by the even-odd rule at the voxel centres (ReadRTStructAsLabelImage()) gives back every
 * voxel. Points are in patient coordinates (LPS, mm).
 *
 * \a referenceSeries is the directory of the DICOM image series (CT, MR or PT) the labels belong to; its
 * Patient and Study attributes and its Frame of Reference UID are copied, the structure set references its
 * study, series and every slice (Contour Image Sequence per contour), and the label map must lie on that
 * series' grid: same in-plane orientation (to 1e-4), every label slice at a slice of the series (to 0.01 mm
 * along the normal). The new Series and SOP Instance UIDs are derived from the series UID and the contents
 * (2.25 root, 128-bit hash), so the same inputs give the same file. Written to a temporary name and renamed
 * when complete.
 *
 * Throws an itk::ExceptionObject naming the input at fault, in one line, when: \a referenceSeries holds no
 * image series or several; a label slice has no slice of the series; the orientation differs; a name is
 * empty, longer than 64 characters or holds a backslash, or two names differ only in case or surrounding spaces (the
 * reader matches them so); no entry of \a roiNames holds a voxel; the file cannot be written. \ingroup
 * BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT void
WriteRTStruct(const DicomRTLabelImageType *               labels,
              const std::map<std::int32_t, std::string> & roiNames,
              const std::string &                         referenceSeries,
              const std::string &                         path);

/** \brief Writes a dose image [Gy] as a DICOM RT Dose (physical dose, Gy) in the frame of reference of a
 * series.
 *
 * The grid is the image's own: origin -> Image Position (Patient), the first two direction columns -> Image
 * Orientation (Patient), spacing -> Pixel Spacing and the Grid Frame Offset Vector (relative to the first
 * frame, negative when the third axis points against the row x column normal). Values: 32-bit unsigned
 * integers, v = round(D / s) with the Dose Grid Scaling s = max D / (2^32 - 1) (as written in the file, so
 * the round trip error is at most s / 2); Dose Summation Type PLAN, with the referenced plan's SOP Instance
 * when \a referencedPlanUID is given. Patient, Study and Frame of Reference come from \a referenceSeries
 * (WriteRTStruct()); the image need not lie on its grid.
 *
 * Throws an itk::ExceptionObject naming the input at fault, in one line, when a dose is negative or not
 * finite, the grid has more than 65535 rows or columns, the third axis is oblique to the row x column normal, \a
 * referenceSeries holds no image series or several, or the file cannot be written. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT void
WriteRTDose(const DicomRTDoseImageType * dose,
            const std::string &          referenceSeries,
            const std::string &          path,
            const std::string &          referencedPlanUID = std::string());

/** \brief Writes a fixed -> moving displacement field as a DICOM Deformable Spatial Registration object (SOP
 * class 1.2.840.10008.5.1.4.1.1.66.3, modality REG), what SlicerRT and planning systems exchange.
 *
 * The registered frame of reference is the fixed scan's (\a fixedSeries: Patient, Study and Frame of Reference
 * are copied from it), the source frame the moving scan's (\a movingSeries: its Frame of Reference UID, and a
 * reference to each of its images, in this study's Referenced Series Sequence or, for another study, the Studies
 * Containing Other Referenced Instances Sequence). PS3.3 C.20.3.1.1 maps a registered point x to the source point
 * M_post(M_pre x + D(x)); both matrices are written as the identity (RIGID), so D is \a field: at the centre of
 * each voxel of its grid (LPS mm) the displacement to the moving scan [mm], as 32-bit floats (exact to a relative
 * 6e-8), x fastest. The grid is the field's: Image Position and Orientation (Patient), Grid Dimensions, Grid
 * Resolution; a third axis against the row x column normal is written slice-reversed, so that it runs along it.
 * Content Date and Time: now (UTC), or the time SOURCE_DATE_EPOCH names when it is set; UIDs are derived from
 * the contents (WriteRTStruct()), so with SOURCE_DATE_EPOCH the same inputs give the same bytes. Written to a
 * temporary name and renamed when complete.
 *
 * Throws an itk::ExceptionObject naming the input at fault, in one line, when the field is missing, holds a
 * non-finite vector, has an oblique third axis or more than 357 million voxels, either directory holds no image
 * series or several, or the file cannot be written. \ingroup BiomechanicalRegistration
 * BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT void
WriteDeformableSpatialRegistration(const DicomRTDisplacementFieldType * field,
                                   const std::string &                  fixedSeries,
                                   const std::string &                  movingSeries,
                                   const std::string &                  path);

} // namespace itk

#endif

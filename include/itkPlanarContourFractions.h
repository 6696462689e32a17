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
#ifndef itkPlanarContourFractions_h
#define itkPlanarContourFractions_h

#include "BiomechanicalRegistrationExport.h"
#include "itkImage.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace itk {

/** One closed planar contour, as an RTSTRUCT holds it: its points in patient coordinates [LPS mm], the last joined
 * to the first. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
struct PlanarContour
{
  std::vector<ImageBase<3>::PointType> points;
};

/** Per-voxel area fractions in [0, 1]. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
using ContourFractionImageType = Image<float, 3>;

/** \brief The fraction of each voxel's in-plane square that the contours enclose, on the slice each contour lies on.
 *
 * Each contour is assigned to the slice of \a referenceGrid whose centre it lies on, as
 * ReadRTStructAsLabelImage() does (every point within half a slice of one slice index). On that slice the region
 * is the even-odd interior of all its contours (holes and several pieces work), and voxel (i, j) gets
 * \f[ f_{ij} = \int_{j-1/2}^{j+1/2} \big| R \cap \{ (x, y) : i - 1/2 \le x \le i + 1/2 \} \big|_x \, dy, \f]
 * in continuous index units: the covered length along x is exact (the crossings of the row with the polygon's
 * edges), the integral over y the midpoint rule on SubRowsPerVoxel sub-rows, exact wherever no vertex lies inside
 * the voxel's rows and otherwise within \f$ O(1 / \mathrm{SubRowsPerVoxel}^2) \f$ of a voxel's area. Slices
 * without a contour are 0. The result has the grid's geometry (0-based region).
 *
 * This is the sub-voxel information an RTSTRUCT carries beyond its voxelization: the organ's surface as the 0.5
 * level of these fractions, interpolated trilinearly (ComputeProbabilityDistanceMap()), follows the polygons
 * in-plane to a small fraction of a voxel and runs linearly between neighbouring slices' outlines; above an
 * organ's last contour it closes halfway to the next slice, as the voxel faces do.
 *
 * Throws itk::ExceptionObject naming \a what and the contour when a contour has fewer than 3 points or a
 * non-finite one, does not lie in one slice, lies on no slice of the grid, or leaves the grid in-plane by more than
 * half a voxel. \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT ContourFractionImageType::Pointer
                                 PlanarContourAreaFractions(const std::vector<PlanarContour> & contours,
                                                            const ImageBase<3> *               referenceGrid,
                                                            const std::string &                what);

/** \brief The outlines of \a value's voxels on slice \a k of \a labels, in the continuous index (i, j) of the
 * slice: marching squares (itk::ContourExtractor2DImageFilter) at the 0.5 level of the slice's indicator padded by
 * one voxel of background, so every ring closes and runs halfway between the outermost voxel centres and their
 * neighbours, one vertex per voxel edge the border crosses; holes are rings of their own; no ring repeats its first
 * vertex. Empty when the slice holds no such voxel.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationDicomRT */
BiomechanicalRegistration_EXPORT std::vector<std::vector<std::array<double, 2>>>
LabelOutlinesOnSlice(const Image<std::int32_t, 3> * labels, std::int32_t value, IndexValueType k);

/** Sub-rows per voxel row of PlanarContourAreaFractions()'s midpoint rule. */
constexpr unsigned int SubRowsPerVoxel = 16;

} // namespace itk

#endif

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
// Internal: planar contours in a grid's continuous index space, shared by the RTSTRUCT reader's even-odd fill and
// the area fractions.
#ifndef itkPlanarContours_h
#define itkPlanarContours_h

#include "itkPlanarContourFractions.h"

#include <map>
#include <string>
#include <vector>

namespace itk {
namespace detail {

/** An edge of a contour in the continuous index space of a slice (i, j). */
struct ContourEdge
{
  double x0, y0, x1, y1;
};

/** The edges of \a contours (those of one ROI, named by \a owner) per slice index of \a grid, indices relative to its
 * region's start. Failures go to bmr::Fail(\a where, \a owner + ", contour c ..."): a contour that matches no slice,
 * is not parallel to them, leaves the grid in-plane, has fewer than 3 points or a non-finite one. */
std::map<long, std::vector<ContourEdge>>
ContourEdgesPerSlice(const std::vector<PlanarContour> & contours,
                     const ImageBase<3> *               grid,
                     const char *                       where,
                     const std::string &                owner);

/** The crossings (x) of row y with \a edges, sorted: an edge crosses when its ends lie on different sides of y (one
 * end strictly above), so a vertex on the row is counted once and the count along a row of closed contours is even;
 * consecutive pairs bound the even-odd interior. */
void
RowCrossings(const std::vector<ContourEdge> & edges, double y, std::vector<double> & crossings);

} // namespace detail
} // namespace itk

#endif

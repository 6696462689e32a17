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
#ifndef bmrGridGeometry_h
#define bmrGridGeometry_h

#include "BiomechanicalRegistrationExport.h"

#include <array>
#include <cstddef>

namespace bmr {

/** \brief Geometry of a 3-D image grid, as ITK defines it.
 *
 * x = origin + D diag(spacing) i, where i is the (continuous) index, D the
 * direction cosine matrix (row-major), all in LPS millimeters. Buffers on the
 * grid are stored with index 0 fastest: offset = i0 + size0 (i1 + size1 i2).
 * \ingroup BiomechanicalRegistration
 */
struct BiomechanicalRegistration_EXPORT GridGeometry
{
  std::array<std::size_t, 3> size{ { 0, 0, 0 } };
  std::array<double, 3>      origin{ { 0, 0, 0 } };
  std::array<double, 3>      spacing{ { 1, 1, 1 } };
  std::array<double, 9>      direction{ { 1, 0, 0, 0, 1, 0, 0, 0, 1 } };

  std::size_t
  GetNumberOfVoxels() const
  {
    return size[0] * size[1] * size[2];
  }

  /** Physical point of a continuous index. */
  std::array<double, 3>
  IndexToPoint(const std::array<double, 3> & index) const;

  /** Continuous index of a physical point (exact inverse of IndexToPoint). */
  std::array<double, 3>
  PointToIndex(const std::array<double, 3> & point) const;

  /** Throws itk::ExceptionObject when the spacing is not positive and finite or
   * the direction matrix is singular; \a what names the grid in the message. */
  void
  Validate(const char * what) const;
};

/** A grid of \a size voxels of \a spacing [mm], rotated by \a rotationZ [rad] about the superior (z) axis,
 * whose centre is the physical origin. */
BiomechanicalRegistration_EXPORT GridGeometry
CenteredGrid(const std::array<std::size_t, 3> & size, const std::array<double, 3> & spacing, double rotationZ = 0.0);

} // namespace bmr

#endif

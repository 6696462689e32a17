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
// The inverse of a 3x3 matrix, shared by the rasterizer and the point locator (private to src/field).
#ifndef bmrMatrix3_h
#define bmrMatrix3_h

namespace bmr {
namespace field {

/** Inverse of a row-major 3x3 matrix; returns the determinant. */
inline double
Invert3(const double m[9], double inv[9])
{
  const double det =
    m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
  const double s = 1.0 / det;
  inv[0] = (m[4] * m[8] - m[5] * m[7]) * s;
  inv[1] = (m[2] * m[7] - m[1] * m[8]) * s;
  inv[2] = (m[1] * m[5] - m[2] * m[4]) * s;
  inv[3] = (m[5] * m[6] - m[3] * m[8]) * s;
  inv[4] = (m[0] * m[8] - m[2] * m[6]) * s;
  inv[5] = (m[2] * m[3] - m[0] * m[5]) * s;
  inv[6] = (m[3] * m[7] - m[4] * m[6]) * s;
  inv[7] = (m[1] * m[6] - m[0] * m[7]) * s;
  inv[8] = (m[0] * m[4] - m[1] * m[3]) * s;
  return det;
}

} // namespace field
} // namespace bmr

#endif

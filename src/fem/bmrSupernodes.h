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
#ifndef bmrSupernodes_h
#define bmrSupernodes_h

// The supernodal layout of a CHOLMOD factor, shared by the factorization and the solves (private to src/fem).
#include <cholmod.h>

#include <cstddef>
#include <cstdint>

namespace bmr {
namespace fem {

/** The supernodal arrays of a CHOLMOD factor with int indices: supernode s holds the columns first[s] to
 * first[s + 1] - 1 as an nsrow x nscol column-major block (leading dimension nsrow) whose rows are listed, ascending,
 * in rows[rowsAt[s]] ... (its own columns first, then the rows below its diagonal block). */
struct Supernodes
{
  const int * first;    // first column of each supernode (nsuper + 1)
  const int * rowsAt;   // start of each supernode's row indices in rows (nsuper + 1)
  const int * valuesAt; // start of each supernode's block in values
  const int * rows;
  double *    values;

  explicit Supernodes(const cholmod_factor & L)
    : first(static_cast<const int *>(L.super))
    , rowsAt(static_cast<const int *>(L.pi))
    , valuesAt(static_cast<const int *>(L.px))
    , rows(static_cast<const int *>(L.s))
    , values(static_cast<double *>(L.x))
  {}
  int
  Columns(std::int32_t s) const
  {
    return first[s + 1] - first[s];
  }
  int
  Rows(std::int32_t s) const
  {
    return rowsAt[s + 1] - rowsAt[s];
  }
  double *
  Block(std::int32_t s) const
  {
    return values + valuesAt[s];
  }
  std::size_t
  BlockSize(std::int32_t s) const
  {
    return static_cast<std::size_t>(Columns(s)) * static_cast<std::size_t>(Rows(s));
  }
};

} // namespace fem
} // namespace bmr

#endif

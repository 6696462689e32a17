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
#ifndef bmrNpzWriter_h
#define bmrNpzWriter_h

#include <cstdint>
#include <string>
#include <vector>

namespace bmr {

/** One array of a NumPy .npz archive: its values as little-endian bytes of NumPy type \c descr ("<f4", "<f8"),
 * in C order (last index fastest) or Fortran order (first index fastest). */
struct NpyArray
{
  std::string                name; ///< the key np.load() gives it (the entry is name + ".npy")
  std::string                descr;
  std::vector<std::uint64_t> shape;
  bool                       fortranOrder{ false };
  std::vector<char>          bytes;

  /** A float64 array in C order. */
  static NpyArray
  Float64(const std::string & name, const std::vector<double> & values, const std::vector<std::uint64_t> & shape);
};

/** Writes \a arrays as an uncompressed .npz (a ZIP archive of .npy version 1.0 files, read by numpy.load) through a
 * temporary file, so the archive is complete or absent. Deterministic: the entries carry a fixed date
 * (1980-01-01). Throws naming \a path when an entry or the archive would pass ZIP's 4 GiB limit (no ZIP64) or
 * the file cannot be written. */
void
WriteNpz(const std::string & path, const std::vector<NpyArray> & arrays);

} // namespace bmr

#endif

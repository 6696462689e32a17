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
#ifndef bmrHash_h
#define bmrHash_h

#include <cstddef>
#include <cstdint>

namespace bmr {

/** The 64-bit FNV-1a offset basis, the usual start of Fnv1a(). */
constexpr std::uint64_t FnvOffsetBasis = 0xcbf29ce484222325ULL;

/** 64-bit FNV-1a over the \a bytes bytes at \a data, continuing from \a hash:
 * \f$ h \leftarrow (h \oplus b) \cdot 1099511628211 \f$ per byte b. A fingerprint of contents (meshes made for
 * which inputs, derived DICOM UIDs, a field's bits), not a cryptographic hash. */
inline std::uint64_t
Fnv1a(const void * data, std::size_t bytes, std::uint64_t hash)
{
  const auto * p = static_cast<const unsigned char *>(data);
  for (std::size_t i = 0; i < bytes; ++i)
  {
    hash = (hash ^ p[i]) * 1099511628211ULL;
  }
  return hash;
}

} // namespace bmr

#endif

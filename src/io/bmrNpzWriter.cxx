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
// NumPy's .npz: a ZIP archive (PKWARE APPNOTE 6.3, "stored" entries, no ZIP64) of .npy files (NumPy's format
// version 1.0: magic, header length, a Python dict literal, the raw values).
#include "bmrNpzWriter.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"

#include <zlib.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

namespace bmr {
namespace {
constexpr const char *  Where = "WriteNpz";
constexpr std::uint16_t DosDate1980 = (0 << 9) | (1 << 5) | 1; // 1980-01-01, ZIP's earliest date
constexpr std::uint64_t ZipLimit = std::numeric_limits<std::uint32_t>::max();

/** The .npy 1.0 header: magic, version, length, dict, padded with spaces and a newline to a multiple of 64. */
std::string
NpyHeader(const NpyArray & array)
{
  std::string shape;
  for (std::size_t i = 0; i < array.shape.size(); ++i)
  {
    shape += (i > 0 ? ", " : "") + std::to_string(array.shape[i]);
  }
  shape = "(" + shape + (array.shape.size() == 1 ? ",)" : ")"); // a 1-tuple keeps its comma
  std::string dict = "{'descr': '" + array.descr + "', 'fortran_order': " + (array.fortranOrder ? "True" : "False") +
                     ", 'shape': " + shape + ", }";
  const std::size_t prefix = 10; // magic (6), version (2), header length (2)
  dict.append(63 - (prefix + dict.size()) % 64, ' ');
  dict += '\n';
  std::string header("\x93NUMPY\x01\x00", 8);
  header += static_cast<char>(dict.size() & 0xff);
  header += static_cast<char>(dict.size() >> 8);
  return header + dict;
}

void
Put16(std::string & out, std::uint16_t v)
{
  out += static_cast<char>(v & 0xff);
  out += static_cast<char>(v >> 8);
}

void
Put32(std::string & out, std::uint32_t v)
{
  Put16(out, static_cast<std::uint16_t>(v & 0xffff));
  Put16(out, static_cast<std::uint16_t>(v >> 16));
}

/** The fields a local file header and a central directory header share, from "version needed" to the name's
 * length and the extra field's (0). */
std::string
EntryFields(std::uint32_t crc, std::uint32_t size, const std::string & name)
{
  std::string out;
  Put16(out, 20); // version needed: 2.0
  Put16(out, 0);  // flags
  Put16(out, 0);  // method: stored
  Put16(out, 0);  // time 00:00:00
  Put16(out, DosDate1980);
  Put32(out, crc);
  Put32(out, size); // compressed
  Put32(out, size); // uncompressed
  Put16(out, static_cast<std::uint16_t>(name.size()));
  Put16(out, 0);
  return out;
}

std::uint32_t
Crc32(std::uint32_t crc, const char * data, std::size_t size)
{
  for (std::size_t done = 0; done < size;) // zlib takes 32-bit lengths
  {
    const auto chunk = static_cast<uInt>(std::min<std::size_t>(size - done, 1u << 30));
    crc = static_cast<std::uint32_t>(crc32(crc, reinterpret_cast<const Bytef *>(data + done), chunk));
    done += chunk;
  }
  return crc;
}
} // namespace

NpyArray
NpyArray::Float64(const std::string &                name,
                  const std::vector<double> &        values,
                  const std::vector<std::uint64_t> & shape)
{
  NpyArray array{ name, "<f8", shape, false, {} };
  array.bytes.resize(values.size() * sizeof(double));
  std::memcpy(array.bytes.data(), values.data(), array.bytes.size());
  return array;
}

void
WriteNpz(const std::string & path, const std::vector<NpyArray> & arrays)
{
  const std::string temporary = TemporaryPathFor(path);
  std::ofstream     out(temporary, std::ios::binary);
  if (!out)
  {
    Fail(Where, "cannot write \"" + path + "\" (is its directory missing or read-only?)");
  }
  std::string   directory;
  std::uint64_t offset = 0;
  for (const NpyArray & array : arrays)
  {
    const std::string   name = array.name + ".npy";
    const std::string   header = NpyHeader(array);
    const std::uint64_t size = header.size() + array.bytes.size();
    if (size > ZipLimit || offset > ZipLimit)
    {
      std::remove(temporary.c_str());
      Fail(Where,
           "cannot write \"" + path + "\": the array \"" + array.name +
             "\" would pass the 4 GiB of a ZIP without ZIP64");
    }
    const std::uint32_t crc = Crc32(Crc32(0, header.data(), header.size()), array.bytes.data(), array.bytes.size());
    std::string         local;
    Put32(local, 0x04034b50);
    local += EntryFields(crc, static_cast<std::uint32_t>(size), name) + name;
    out.write(local.data(), std::streamsize(local.size()));
    out.write(header.data(), std::streamsize(header.size()));
    out.write(array.bytes.data(), std::streamsize(array.bytes.size()));

    Put32(directory, 0x02014b50);
    Put16(directory, 20); // made by: 2.0, MS-DOS attributes
    directory += EntryFields(crc, static_cast<std::uint32_t>(size), name);
    Put16(directory, 0); // comment length
    Put16(directory, 0); // disk
    Put16(directory, 0); // internal attributes
    Put32(directory, 0); // external attributes
    Put32(directory, static_cast<std::uint32_t>(offset));
    directory += name;
    offset += local.size() + size;
  }
  if (offset > ZipLimit)
  {
    std::remove(temporary.c_str());
    Fail(Where, "cannot write \"" + path + "\": the archive would pass the 4 GiB of a ZIP without ZIP64");
  }
  std::string end;
  Put32(end, 0x06054b50);
  Put16(end, 0);
  Put16(end, 0);
  Put16(end, static_cast<std::uint16_t>(arrays.size()));
  Put16(end, static_cast<std::uint16_t>(arrays.size()));
  Put32(end, static_cast<std::uint32_t>(directory.size()));
  Put32(end, static_cast<std::uint32_t>(offset));
  Put16(end, 0);
  out << directory << end;
  out.close();
  if (!out)
  {
    std::remove(temporary.c_str());
    Fail(Where, "writing \"" + path + "\" failed (disk full?)");
  }
  CommitTemporaryFile(temporary, path);
}

} // namespace bmr

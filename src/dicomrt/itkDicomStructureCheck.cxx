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
// The structure check of DICOM Part 10 files that runs before GDCM sees a file (GDCM is not used here).
#include "itkDicomStructureCheck.h"

#include "bmrError.h"
#include "itkDicomRTCommon.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <set>
#include <sstream>

namespace itk {
namespace dicomrt {
namespace {

/** Walks the data elements of a DICOM Part 10 file without interpreting their values, to refuse a truncated or
 * corrupt file before GDCM parses it: Debian's GDCM is built with assertions, and its reader aborts the
 * process on some malformed files instead of failing (after a failed first pass over a truncated file it
 * asserts on the exhausted stream; a sequence delimiter where an element is expected fails an assertion).
 * The grammar checked (PS3.5 7.1, 7.5): a data set is a list of elements, each ending inside the file and
 * inside its parent; a sequence (SQ; in implicit VR, any element of undefined length) holds only items
 * (FFFE,E000), ended by its length or by a sequence delimiter (FFFE,E0DD); an item holds a data set, ended by
 * its length or by an item delimiter (FFFE,E00D); encapsulated pixel data (OB/OW of undefined length) hold
 * fragments (items of defined length) up to a sequence delimiter. Defined-length sequences are walked too in
 * explicit VR; in implicit VR a defined-length sequence cannot be told from a value and is only bounded. */
class DicomStructureWalker
{
public:
  explicit DicomStructureWalker(std::vector<unsigned char> bytes)
    : m_Bytes(std::move(bytes))
  {}

  /** An empty string when the structure is complete, else what is wrong. With \a stopAtModality, stops at the
   * Modality (0008,0060) or where it would have been: a prefix of the file suffices. */
  std::string
  Check(bool stopAtModality = false)
  {
    if (m_Bytes.size() < 132 || std::memcmp(m_Bytes.data() + 128, "DICM", 4) != 0)
    {
      return "no DICOM preamble";
    }
    // The File Meta Information (group 0002) is explicit VR little endian; its transfer syntax says how the
    // data set that follows is encoded.
    std::size_t pos = 132;
    std::string transferSyntax;
    while (pos + 4 <= m_Bytes.size() && Uint16(pos) == 0x0002)
    {
      const std::uint16_t element = Uint16(pos + 2);
      if (!Element(pos, m_Bytes.size(), 0))
      {
        return m_Problem;
      }
      if (element == 0x0010)
      {
        transferSyntax = m_Value;
      }
    }
    // PS3.10 7.1: the File Meta Information, with its Transfer Syntax UID, follows the preamble of every Part 10
    // file. Without it GDCM guesses the encoding, and on a corrupt group tag spends seconds doing so.
    if (pos == 132)
    {
      return "no File Meta Information (group 0002) after the preamble";
    }
    if (transferSyntax.empty())
    {
      return "no Transfer Syntax UID (0002,0010) in the File Meta Information";
    }
    if (transferSyntax == "1.2.840.10008.1.2.1.99")
    {
      return std::string(); // deflated: the data set cannot be walked without inflating it; left to GDCM
    }
    m_ExplicitVR = transferSyntax != "1.2.840.10008.1.2";
    m_BigEndian = transferSyntax == "1.2.840.10008.1.2.2";
    while (pos < m_Bytes.size())
    {
      if (pos + 4 > m_Bytes.size())
      {
        return "ends inside an element header (truncated)";
      }
      const std::uint16_t group = Uint16(pos), element = Uint16(pos + 2);
      if (stopAtModality && (group > 0x0008 || (group == 0x0008 && element > 0x0060)))
      {
        return std::string();
      }
      if (!Element(pos, m_Bytes.size(), 0))
      {
        return m_Problem;
      }
      if (group == 0x0008 && element == 0x0060)
      {
        m_Modality = Upper(m_Value);
        if (stopAtModality)
        {
          return std::string();
        }
      }
    }
    return std::string();
  }

  /** The Modality found by Check(), upper case without padding; empty when there is none. */
  const std::string &
  Modality() const
  {
    return m_Modality;
  }

private:
  static constexpr std::uint32_t UndefinedLength = 0xffffffff;
  static constexpr unsigned int  MaximumDepth = 64;

  std::uint16_t
  Uint16(std::size_t pos) const
  {
    const unsigned char * b = m_Bytes.data() + pos;
    return m_BigEndian ? static_cast<std::uint16_t>(b[0] << 8 | b[1]) : static_cast<std::uint16_t>(b[1] << 8 | b[0]);
  }
  std::uint32_t
  Uint32(std::size_t pos) const
  {
    const std::uint32_t first = Uint16(pos), second = Uint16(pos + 2);
    return m_BigEndian ? (first << 16 | second) : (second << 16 | first);
  }
  bool
  Fail(const std::string & problem)
  {
    m_Problem = problem;
    return false;
  }
  bool
  IsTag(std::size_t pos, std::uint16_t element) const
  {
    return Uint16(pos) == 0xfffe && Uint16(pos + 2) == element;
  }

  /** One element of a data set at \a pos, ending by \a end. */
  bool
  Element(std::size_t & pos, std::size_t end, unsigned int depth)
  {
    if (depth > MaximumDepth)
    {
      return Fail("sequences nested deeper than 64 levels");
    }
    if (pos + 8 > end)
    {
      return Fail("ends inside an element header (truncated)");
    }
    const std::uint16_t group = Uint16(pos), element = Uint16(pos + 2);
    std::ostringstream  name;
    name << "(" << std::hex << std::setfill('0') << std::setw(4) << group << "," << std::setw(4) << element << ")";
    if (group == 0xfffe)
    {
      return Fail("an item or delimiter tag " + name.str() + " where a data element belongs");
    }
    std::string   vr;
    std::uint32_t length = 0;
    if (m_ExplicitVR || group == 0x0002)
    {
      vr.assign(reinterpret_cast<const char *>(m_Bytes.data()) + pos + 4, 2);
      // An unknown VR sends GDCM's reader into its implicit-VR fallback, which asserts (see above).
      static const std::set<std::string> knownVRs{ "AE", "AS", "AT", "CS", "DA", "DS", "DT", "FL", "FD",
                                                   "IS", "LO", "LT", "OB", "OD", "OF", "OL", "OV", "OW",
                                                   "PN", "SH", "SL", "SQ", "SS", "ST", "SV", "TM", "UC",
                                                   "UI", "UL", "UN", "UR", "US", "UT", "UV" };
      if (!knownVRs.count(vr))
      {
        return Fail("element " + name.str() + " has no valid VR");
      }
      static const std::set<std::string> longVRs{ "OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                                  "SV", "UC", "UN", "UR", "UT", "UV" };
      if (longVRs.count(vr))
      {
        if (pos + 12 > end)
        {
          return Fail("ends inside the header of element " + name.str() + " (truncated)");
        }
        length = Uint32(pos + 8);
        pos += 12;
      }
      else
      {
        length = Uint16(pos + 6);
        pos += 8;
      }
    }
    else
    {
      length = Uint32(pos + 4);
      pos += 8;
    }
    if (vr == "SQ" || (vr.empty() && length == UndefinedLength))
    {
      return Sequence(pos, end, length, depth, name.str());
    }
    if (length == UndefinedLength)
    {
      if (vr == "OB" || vr == "OW" || vr == "UN")
      {
        // Encapsulated pixel data (fragments) or a UN sequence: items up to a sequence delimiter.
        return Sequence(pos, end, length, depth, name.str(), vr != "UN");
      }
      return Fail("element " + name.str() + " of VR " + vr + " has an undefined length");
    }
    if (length > end - pos)
    {
      return Fail("the value of element " + name.str() + " ends beyond its end (truncated)");
    }
    // The text of a short value (the transfer syntax, the modality) without its padding.
    m_Value.assign(reinterpret_cast<const char *>(m_Bytes.data()) + pos, std::min<std::uint32_t>(length, 64));
    m_Value = Trim(m_Value.substr(0, m_Value.find('\0')));
    pos += length;
    return true;
  }

  /** The items of a sequence whose value starts at \a pos: \a length bytes, or up to a sequence delimiter; with
   * \a fragments, the items are the fragments of encapsulated pixel data. */
  bool
  Sequence(std::size_t &       pos,
           std::size_t         end,
           std::uint32_t       length,
           unsigned int        depth,
           const std::string & name,
           bool                fragments = false)
  {
    if (length != UndefinedLength)
    {
      if (length > end - pos)
      {
        return Fail("sequence " + name + " ends beyond its end (truncated)");
      }
      end = pos + length;
    }
    while (length == UndefinedLength || pos < end)
    {
      if (pos + 8 > end)
      {
        return Fail("sequence " + name + " ends inside an item header (truncated)");
      }
      const std::uint32_t itemLength = Uint32(pos + 4);
      if (length == UndefinedLength && IsTag(pos, 0xe0dd))
      {
        pos += 8;
        return true;
      }
      if (!IsTag(pos, 0xe000))
      {
        return Fail("sequence " + name + " holds something other than items");
      }
      pos += 8;
      if (itemLength == UndefinedLength)
      {
        if (!ItemUpToDelimiter(pos, end, depth + 1, name))
        {
          return false;
        }
        continue;
      }
      if (itemLength > end - pos)
      {
        return Fail("an item of sequence " + name + " ends beyond its end (truncated)");
      }
      const std::size_t itemEnd = pos + itemLength;
      // Fragments of encapsulated pixel data are bytes; items of a sequence hold data sets (walked in explicit VR).
      while (!fragments && m_ExplicitVR && pos < itemEnd)
      {
        if (!Element(pos, itemEnd, depth + 1))
        {
          return false;
        }
      }
      pos = itemEnd;
    }
    return true;
  }

  /** The data set of an item of undefined length, up to its item delimiter. */
  bool
  ItemUpToDelimiter(std::size_t & pos, std::size_t end, unsigned int depth, const std::string & name)
  {
    while (pos + 8 <= end)
    {
      if (IsTag(pos, 0xe00d))
      {
        pos += 8;
        return true;
      }
      if (!Element(pos, end, depth))
      {
        return false;
      }
    }
    return Fail("an item of sequence " + name + " has no item delimiter (truncated)");
  }

  std::vector<unsigned char> m_Bytes;
  bool                       m_ExplicitVR{ true };
  bool                       m_BigEndian{ false };
  std::string                m_Problem;
  std::string                m_Value;    ///< of the last element of defined length (its first 64 bytes)
  std::string                m_Modality; ///< (0008,0060) of the top-level data set
};

/** The bytes of \a path; false when it cannot be read. */
bool
ReadBytes(const std::string & path, std::vector<unsigned char> & bytes)
{
  std::ifstream file(path, std::ios::binary);
  if (!file)
  {
    return false;
  }
  bytes.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
  return !file.bad();
}

} // namespace

std::string
DicomStructureProblem(std::vector<unsigned char> bytes)
{
  return DicomStructureWalker(std::move(bytes)).Check();
}

std::string
DicomModalityOfPrefix(std::vector<unsigned char> prefix)
{
  DicomStructureWalker walker(std::move(prefix));
  return walker.Check(true).empty() ? walker.Modality() : std::string();
}

} // namespace dicomrt

namespace {
/** What is wrong with the structure of \a path when it is a DICOM Part 10 file; empty otherwise. */
std::string
FileProblem(const std::string & path)
{
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error) || !dicomrt::HasPart10Preamble(path))
  {
    return std::string();
  }
  std::vector<unsigned char> bytes;
  if (!dicomrt::ReadBytes(path, bytes))
  {
    return "cannot be read";
  }
  const std::string problem = dicomrt::DicomStructureProblem(std::move(bytes));
  return problem.empty() ? problem : "is corrupt: " + problem;
}
} // namespace

void
CheckDicomFileStructure(const std::string & path, const std::string & what)
{
  const std::string problem = FileProblem(path);
  if (!problem.empty())
  {
    bmr::Fail("CheckDicomFileStructure", what + " \"" + path + "\" " + problem);
  }
}

void
CheckDicomDirectoryStructure(const std::string & directory, const std::string & what)
{
  std::error_code          error;
  std::vector<std::string> files;
  for (const auto & entry : std::filesystem::directory_iterator(directory, error))
  {
    files.push_back(entry.path().string());
  }
  // Sorted, so that of several corrupt files the same one is named on every file system.
  std::sort(files.begin(), files.end());
  for (const std::string & file : files)
  {
    const std::string problem = FileProblem(file);
    if (!problem.empty())
    {
      bmr::Fail("CheckDicomDirectoryStructure",
                what + " \"" + directory + "\": its DICOM file \"" + std::filesystem::path(file).filename().string() +
                  "\" " + problem);
    }
  }
}

} // namespace itk

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
#include "itkDicomRTCommon.h"

#include "itkDicomRT.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"
#include "bmrHash.h"
#include "itkDicomStructureCheck.h"
#include "itkGDCMSeriesFileNames.h"

#include "gdcmItem.h"
#include "gdcmReader.h"
#include "gdcmTrace.h"
#include "gdcmWriter.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

namespace itk {

std::map<std::int32_t, std::string>
SceneROINames(const bmr::Scene & scene)
{
  std::map<std::int32_t, std::string> names;
  for (const bmr::SceneLabel & label : scene.labels)
  {
    if (label.role != bmr::LabelRoleEnum::Outside)
    {
      names[label.value] = label.name;
    }
  }
  return names;
}

namespace dicomrt {
namespace {
const gdcm::Tag PixelDataTag(0x7fe0, 0x0010);

/** The data set of \a file up to its pixel data; fails naming \a file when it cannot be parsed. */
gdcm::DataSet
ReadHeader(const std::string & file, const char * where)
{
  CheckDicomFileStructure(file, "reference series file");
  gdcm::Reader reader;
  reader.SetFileName(file.c_str());
  if (!reader.ReadUpToTag(PixelDataTag, std::set<gdcm::Tag>()))
  {
    bmr::FailInput(where, "reference series file \"" + file + "\" is not a readable DICOM file");
  }
  return reader.GetFile().GetDataSet();
}

bool
IsRTObject(const std::string & modality)
{
  static const std::set<std::string> rt = { "RTSTRUCT", "RTDOSE", "RTPLAN", "RTRECORD", "REG", "SEG", "SR" };
  return rt.count(modality) > 0;
}

/** The files of the one image series of \a directory (RT objects and other non-images are not series). */
std::vector<std::string>
ImageSeriesFiles(const std::string & directory, const char * where)
{
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error))
  {
    bmr::FailInput(where, "reference series \"" + directory + "\" is not a directory of a DICOM image series");
  }
  bool anyDicom = false; // GDCMSeriesFileNames warns on a directory without DICOM files: look first
  for (const auto & entry : std::filesystem::directory_iterator(directory, error))
  {
    anyDicom = anyDicom || (entry.is_regular_file(error) && HasPart10Preamble(entry.path().string()));
  }
  if (!anyDicom)
  {
    bmr::FailInput(where, "reference series \"" + directory + "\" holds 0 DICOM image series (no DICOM file)");
  }
  CheckDicomDirectoryStructure(directory, "reference series"); // GDCM's scanner parses every file
  auto names = GDCMSeriesFileNames::New();
  names->SetUseSeriesDetails(false);
  names->SetDirectory(directory);
  std::vector<std::vector<std::string>> images;
  for (const std::string & uid : names->GetSeriesUIDs())
  {
    const std::vector<std::string> files = names->GetFileNames(uid);
    if (!files.empty() && !IsRTObject(StringValue(ReadHeader(files.front(), where), gdcm::Tag(0x0008, 0x0060))))
    {
      images.push_back(files);
    }
  }
  if (images.size() != 1)
  {
    bmr::FailInput(where,
                   "reference series \"" + directory + "\" holds " + std::to_string(images.size()) +
                     " DICOM image series; exactly one (the CT the RT object belongs to) is needed");
  }
  return images.front();
}

/** The attribute \a tag of \a ds, or a failure naming \a file. */
std::string
Required(const gdcm::DataSet & ds,
         const gdcm::Tag &     tag,
         const char *          name,
         const std::string &   file,
         const char *          where)
{
  const std::string value = StringValue(ds, tag);
  if (value.empty())
  {
    bmr::FailInput(where, "reference series file \"" + file + "\" has no " + name);
  }
  return value;
}

template<std::size_t N>
std::array<double, N>
RequiredNumbers(const gdcm::DataSet & ds,
                const gdcm::Tag &     tag,
                const char *          name,
                const std::string &   file,
                const char *          where)
{
  std::vector<double> values;
  if (!ParseNumbers(Required(ds, tag, name, file, where), values) || values.size() != N)
  {
    bmr::FailInput(where, "reference series file \"" + file + "\" has a malformed " + name);
  }
  std::array<double, N> out;
  std::copy(values.begin(), values.end(), out.begin());
  return out;
}

/** The Patient and General Study attributes an RT object copies from its image series. */
std::vector<std::pair<gdcm::Tag, gdcm::VR::VRType>>
PatientAndStudyAttributes()
{
  return { { gdcm::Tag(0x0008, 0x0020), gdcm::VR::DA }, { gdcm::Tag(0x0008, 0x0030), gdcm::VR::TM },
           { gdcm::Tag(0x0008, 0x0050), gdcm::VR::SH }, { gdcm::Tag(0x0008, 0x0090), gdcm::VR::PN },
           { gdcm::Tag(0x0010, 0x0010), gdcm::VR::PN }, { gdcm::Tag(0x0010, 0x0020), gdcm::VR::LO },
           { gdcm::Tag(0x0010, 0x0030), gdcm::VR::DA }, { gdcm::Tag(0x0010, 0x0040), gdcm::VR::CS },
           { gdcm::Tag(0x0020, 0x000d), gdcm::VR::UI }, { gdcm::Tag(0x0020, 0x0010), gdcm::VR::SH } };
}

std::uint64_t
Fnv1a(const std::string & text, std::uint64_t hash)
{
  hash = bmr::Fnv1a(text.data(), text.size(), hash);
  hash ^= hash >> 33; // the finalizer of MurmurHash3: every input bit reaches every output bit
  hash *= 0xff51afd7ed558ccdULL;
  hash ^= hash >> 33;
  return hash;
}

/** Turns GDCM's diagnostics (printed on std::cerr by Debian's build) off while it lives. */
class QuietGDCM
{
public:
  QuietGDCM()
    : m_Warning(gdcm::Trace::GetWarningFlag())
    , m_Error(gdcm::Trace::GetErrorFlag())
  {
    gdcm::Trace::WarningOff();
    gdcm::Trace::ErrorOff();
  }
  ~QuietGDCM()
  {
    gdcm::Trace::SetWarning(m_Warning);
    gdcm::Trace::SetError(m_Error);
  }
  QuietGDCM(const QuietGDCM &) = delete;
  QuietGDCM &
  operator=(const QuietGDCM &) = delete;

private:
  bool m_Warning;
  bool m_Error;
};

} // namespace

std::string
Trim(const std::string & text)
{
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos)
  {
    return std::string();
  }
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

std::string
Upper(std::string text)
{
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::toupper(c); });
  return text;
}

std::string
NameKey(const std::string & name)
{
  std::string key = Trim(name);
  std::transform(key.begin(), key.end(), key.begin(), [](unsigned char c) { return std::tolower(c); });
  return key;
}

/** The value of a string attribute (CS, DS, IS, LO, UI, ...) without padding (spaces, NUL); empty when absent. */
std::string
StringValue(const gdcm::DataSet & ds, const gdcm::Tag & tag)
{
  if (!ds.FindDataElement(tag))
  {
    return std::string();
  }
  const gdcm::ByteValue * bytes = ds.GetDataElement(tag).GetByteValue();
  if (!bytes || !bytes->GetPointer())
  {
    return std::string();
  }
  std::string text(bytes->GetPointer(), bytes->GetLength());
  text.erase(std::find(text.begin(), text.end(), '\0'), text.end());
  return Trim(text);
}

/** The backslash-separated numbers of a DS or IS value; false when one is not a finite number. */
bool
ParseNumbers(const std::string & text, std::vector<double> & values)
{
  values.clear();
  if (Trim(text).empty())
  {
    return true;
  }
  std::size_t begin = 0;
  while (true)
  {
    const std::size_t end = text.find('\\', begin);
    const std::string item = Trim(text.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
    char *            parsedEnd = nullptr;
    const double      value = std::strtod(item.c_str(), &parsedEnd);
    if (item.empty() || parsedEnd != item.c_str() + item.size() || !std::isfinite(value))
    {
      return false;
    }
    values.push_back(value);
    if (end == std::string::npos)
    {
      return true;
    }
    begin = end + 1;
  }
}

bool
HasPart10Preamble(const std::string & path)
{
  std::ifstream file(path, std::ios::binary);
  char          header[132];
  return file.read(header, sizeof(header)) && std::string(header + 128, 4) == "DICM";
}

ReferencedSeries
ReadReferencedSeries(const std::string & directory, const char * where)
{
  ReferencedSeries series;
  series.directory = directory;
  for (const std::string & file : ImageSeriesFiles(directory, where))
  {
    const gdcm::DataSet ds = ReadHeader(file, where);
    ReferencedImage     image;
    image.sopClassUID = Required(ds, gdcm::Tag(0x0008, 0x0016), "SOP Class UID", file, where);
    image.sopInstanceUID = Required(ds, gdcm::Tag(0x0008, 0x0018), "SOP Instance UID", file, where);
    image.position = RequiredNumbers<3>(ds, gdcm::Tag(0x0020, 0x0032), "Image Position (Patient)", file, where);
    if (series.images.empty())
    {
      series.seriesInstanceUID = Required(ds, gdcm::Tag(0x0020, 0x000e), "Series Instance UID", file, where);
      series.frameOfReferenceUID = Required(ds, gdcm::Tag(0x0020, 0x0052), "Frame of Reference UID", file, where);
      series.orientation =
        RequiredNumbers<6>(ds, gdcm::Tag(0x0020, 0x0037), "Image Orientation (Patient)", file, where);
      Required(ds, gdcm::Tag(0x0020, 0x000d), "Study Instance UID", file, where);
      for (const auto & attribute : PatientAndStudyAttributes())
      {
        Put(series.patientAndStudy, attribute.first, attribute.second, StringValue(ds, attribute.first));
      }
    }
    series.images.push_back(image);
  }
  return series;
}

int
SliceAxisSense(const Matrix<double, 3, 3> & D)
{
  const double normal[3] = { D(1, 0) * D(2, 1) - D(2, 0) * D(1, 1),
                             D(2, 0) * D(0, 1) - D(0, 0) * D(2, 1),
                             D(0, 0) * D(1, 1) - D(1, 0) * D(0, 1) };
  for (const int sense : { 1, -1 })
  {
    bool matches = true;
    for (unsigned int a = 0; a < 3; ++a)
    {
      matches = matches && std::abs(D(a, 2) - sense * normal[a]) <= 1e-4;
    }
    if (matches)
    {
      return sense;
    }
  }
  return 0;
}

gdcm::SmartPointer<gdcm::SequenceOfItems>
Sequence(const gdcm::DataSet & ds, const gdcm::Tag & tag)
{
  if (!ds.FindDataElement(tag))
  {
    return nullptr;
  }
  try
  {
    gdcm::SmartPointer<gdcm::SequenceOfItems> sq = ds.GetDataElement(tag).GetValueAsSQ();
    if (sq && sq->GetNumberOfItems() > 0)
    {
      return sq;
    }
  }
  catch (const std::exception &)
  {
    // An undecodable sequence is reported by the caller as missing.
  }
  return nullptr;
}

std::string
DerivedUID(const std::string & seed)
{
  // Two independent 64-bit hashes make the 128-bit integer of a 2.25 UID (ITU-T X.667, at most 44 characters).
  unsigned __int128 value =
    (static_cast<unsigned __int128>(Fnv1a(seed, 0xcbf29ce484222325ULL)) << 64) | Fnv1a(seed, 0x84222325cbf29ce4ULL);
  std::string digits;
  do
  {
    digits.insert(digits.begin(), static_cast<char>('0' + static_cast<int>(value % 10)));
    value /= 10;
  } while (value != 0);
  return "2.25." + digits;
}

std::string
DecimalString(double value)
{
  char text[32];
  for (int digits = 12; digits > 1; --digits)
  {
    std::snprintf(text, sizeof(text), "%.*g", digits, value);
    if (std::char_traits<char>::length(text) <= 16)
    {
      break;
    }
  }
  return text;
}

std::string
DecimalStrings(const double * values, std::size_t count)
{
  std::string text;
  for (std::size_t i = 0; i < count; ++i)
  {
    text += (i ? "\\" : "") + DecimalString(values[i]);
  }
  return text;
}

void
Put(gdcm::DataSet & ds, const gdcm::Tag & tag, const gdcm::VR & vr, const std::string & value)
{
  std::string padded = value;
  if (padded.size() % 2 != 0)
  {
    padded.push_back(vr == gdcm::VR::UI ? '\0' : ' ');
  }
  gdcm::DataElement element(tag);
  element.SetVR(vr);
  element.SetByteValue(padded.data(), static_cast<std::uint32_t>(padded.size()));
  ds.Replace(element);
}

void
PutSequence(gdcm::DataSet & ds, const gdcm::Tag & tag, const std::vector<gdcm::DataSet> & items)
{
  gdcm::SmartPointer<gdcm::SequenceOfItems> sequence = new gdcm::SequenceOfItems;
  sequence->SetLengthToUndefined();
  for (const gdcm::DataSet & nested : items)
  {
    gdcm::Item item;
    item.SetVLToUndefined();
    item.SetNestedDataSet(nested);
    sequence->AddItem(item);
  }
  gdcm::DataElement element(tag);
  element.SetVR(gdcm::VR::SQ);
  element.SetValue(*sequence);
  element.SetVLToUndefined();
  ds.Replace(element);
}

void
PutCommonModules(gdcm::DataSet &          ds,
                 const ReferencedSeries & series,
                 const std::string &      sopClassUID,
                 const std::string &      modality,
                 const std::string &      contents)
{
  const std::string seed = series.seriesInstanceUID + " " + contents;
  for (const gdcm::DataElement & element : series.patientAndStudy.GetDES())
  {
    ds.Replace(element);
  }
  Put(ds, gdcm::Tag(0x0008, 0x0005), gdcm::VR::CS, "ISO_IR 100");
  Put(ds, gdcm::Tag(0x0008, 0x0016), gdcm::VR::UI, sopClassUID);
  Put(ds, gdcm::Tag(0x0008, 0x0018), gdcm::VR::UI, DerivedUID(modality + " instance " + seed));
  Put(ds, gdcm::Tag(0x0008, 0x0060), gdcm::VR::CS, modality);
  Put(ds, gdcm::Tag(0x0008, 0x0070), gdcm::VR::LO, "ITKBiomechanicalRegistration");
  Put(ds, gdcm::Tag(0x0008, 0x1070), gdcm::VR::PN, ""); // Operators' Name: type 2 in the RT Series module
  Put(ds, gdcm::Tag(0x0008, 0x1090), gdcm::VR::LO, "biomechreg");
  Put(ds, gdcm::Tag(0x0020, 0x000e), gdcm::VR::UI, DerivedUID(modality + " series " + seed));
  Put(ds, gdcm::Tag(0x0020, 0x0011), gdcm::VR::IS, "1");
  Put(ds, gdcm::Tag(0x0020, 0x0052), gdcm::VR::UI, series.frameOfReferenceUID);
  Put(ds, gdcm::Tag(0x0020, 0x1040), gdcm::VR::LO, "");
}

void
WriteDataSetAtomically(const gdcm::DataSet & ds, const std::string & path, const char * where)
{
  const std::string temporary = bmr::TemporaryPathFor(path);
  if (!std::ofstream(temporary, std::ios::binary)) // gdcm::Writer asserts on a file it cannot open
  {
    bmr::Fail(where, "cannot write \"" + path + "\" (is its directory missing or read-only?)");
  }
  gdcm::Writer writer;
  writer.SetFileName(temporary.c_str());
  writer.GetFile().SetDataSet(ds);
  writer.GetFile().GetHeader().SetDataSetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
  if (!writer.Write())
  {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    bmr::Fail(where, "cannot write \"" + path + "\"");
  }
  bmr::CommitTemporaryFile(temporary, path);
}

// ------------------------------------------------------------------------------------------ reading

std::string
Quote(const std::string & text)
{
  return "\"" + text + "\"";
}

/** Throws naming the file: `<kind> "<path>": <message>`. */
[[noreturn]] void
FailFile(const char * where, const std::string & kind, const std::string & path, const std::string & message)
{
  bmr::FailInput(where, kind + " " + Quote(path) + ": " + message);
}

/** Refuses, naming the file, what GDCM must not see: not a file, not DICOM Part 10, or an incomplete structure. */
void
CheckDicomFile(const char * where, const std::string & kind, const std::string & path)
{
  std::ifstream file(path, std::ios::binary);
  if (!file || std::filesystem::is_directory(path))
  {
    FailFile(where, kind, path, "cannot be opened");
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.size() < 132 || std::memcmp(bytes.data() + 128, "DICM", 4) != 0)
  {
    FailFile(where, kind, path, "is not a DICOM file");
  }
  const std::string problem = DicomStructureProblem(std::move(bytes));
  if (!problem.empty())
  {
    FailFile(where, kind, path, "is corrupt: " + problem);
  }
}

std::vector<double>
FileNumbers(const gdcm::DataSet & ds,
            const gdcm::Tag &     tag,
            const std::string &   name,
            std::size_t           count,
            const char *          where,
            const std::string &   kind,
            const std::string &   path)
{
  std::vector<double> values;
  if (!ds.FindDataElement(tag) || !ParseNumbers(StringValue(ds, tag), values) || values.empty() ||
      (count > 0 && values.size() != count))
  {
    std::ostringstream os;
    os << "has no valid " << name << " " << tag << (count > 0 ? " (" + std::to_string(count) + " numbers)" : "");
    FailFile(where, kind, path, os.str());
  }
  return values;
}

bool
OrientationAxes(const std::vector<double> & orientation,
                std::array<double, 3> &     row,
                std::array<double, 3> &     column,
                std::array<double, 3> &     normal)
{
  row = { { orientation[0], orientation[1], orientation[2] } };
  column = { { orientation[3], orientation[4], orientation[5] } };
  normal = { { row[1] * column[2] - row[2] * column[1],
               row[2] * column[0] - row[0] * column[2],
               row[0] * column[1] - row[1] * column[0] } };
  const double rowLength = std::sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2]);
  const double columnLength = std::sqrt(column[0] * column[0] + column[1] * column[1] + column[2] * column[2]);
  const double dot = row[0] * column[0] + row[1] * column[1] + row[2] * column[2];
  return std::abs(rowLength - 1) <= 1e-3 && std::abs(columnLength - 1) <= 1e-3 && std::abs(dot) <= 1e-3;
}

/** Parses \a path with \a reader (a gdcm::Reader or gdcm::ImageReader) after CheckDicomFile(); throws naming the
 * file when GDCM cannot. */
void
ReadParsedFile(gdcm::Reader & reader, const char * where, const std::string & kind, const std::string & path)
{
  QuietGDCM quiet;
  bool      ok = false;
  reader.SetFileName(path.c_str());
  try
  {
    ok = reader.Read();
  }
  catch (const std::exception &)
  {
    ok = false;
  }
  if (!ok)
  {
    FailFile(where, kind, path, "cannot be read as DICOM (corrupt)");
  }
}

void
CheckModality(const gdcm::DataSet & ds, const std::string & expected, const char * where, const std::string & path)
{
  const std::string modality = Upper(StringValue(ds, gdcm::Tag(0x0008, 0x0060)));
  if (modality != expected)
  {
    FailFile(where,
             expected,
             path,
             "is not an " + expected + " (Modality " + (modality.empty() ? "missing" : Quote(modality)) + ")");
  }
}

} // namespace dicomrt
} // namespace itk

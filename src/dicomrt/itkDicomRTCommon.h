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
// What the DICOM-RT reader and writers share: reading attributes, the image series an RT object refers to, and
// building and writing data sets.
#ifndef itkDicomRTCommon_h
#define itkDicomRTCommon_h

#include "gdcmDataSet.h"
#include "gdcmSequenceOfItems.h"
#include "gdcmTag.h"
#include "gdcmVR.h"
#include "itkMatrix.h"

#include <array>
#include <string>
#include <vector>

namespace gdcm {
class Reader;
}

namespace itk {
namespace dicomrt {

/** \a text without leading and trailing white space. */
std::string
Trim(const std::string & text);

/** The key under which ROI names are compared: trimmed, lower case. */
std::string
NameKey(const std::string & name);

/** The value of a string attribute (CS, DS, IS, LO, UI, ...) without padding (spaces, NUL); empty when absent. */
std::string
StringValue(const gdcm::DataSet & ds, const gdcm::Tag & tag);

/** \a text in upper case (ASCII). */
std::string
Upper(std::string text);

/** What is wrong with the structure of the DICOM Part 10 file held in \a bytes (elements, sequences and items
 * ending inside the file and their parents; see itkDicomStructureCheck.cxx); empty when it is complete. */
std::string
DicomStructureProblem(std::vector<unsigned char> bytes);

/** The Modality (0008,0060) of a DICOM Part 10 file from a \a prefix of its bytes, upper case without padding;
 * empty when there is none or the prefix is corrupt up to it. */
std::string
DicomModalityOfPrefix(std::vector<unsigned char> prefix);

/** True when \a path starts with the DICOM part 10 preamble (128 bytes, then "DICM"). */
bool
HasPart10Preamble(const std::string & path);

/** The backslash-separated numbers of a DS or IS value; false when one is not a finite number. */
bool
ParseNumbers(const std::string & text, std::vector<double> & values);

/** One image of the referenced series, in slice order. */
struct ReferencedImage
{
  std::string           sopClassUID;
  std::string           sopInstanceUID;
  std::array<double, 3> position{ { 0, 0, 0 } }; ///< Image Position (Patient) [LPS mm]
};

/** The image series an RT object belongs to: what it copies (patient, study) and what it references. */
struct ReferencedSeries
{
  std::string                  directory;
  std::string                  seriesInstanceUID;
  std::string                  frameOfReferenceUID;
  std::array<double, 6>        orientation{ { 1, 0, 0, 0, 1, 0 } }; ///< Image Orientation (Patient)
  std::vector<ReferencedImage> images;
  gdcm::DataSet                patientAndStudy; ///< the Patient and General Study attributes of the first image
};

/** +1 when the third column of the direction matrix \a D is the normal of its first two (row x column, to 1e-4),
 * -1 when it is its opposite, 0 otherwise (an oblique or sheared stack, which DICOM's grids cannot hold). */
int
SliceAxisSense(const Matrix<double, 3, 3> & D);

/** The sequence at \a tag, or nullptr when it is absent, empty or cannot be decoded. */
gdcm::SmartPointer<gdcm::SequenceOfItems>
Sequence(const gdcm::DataSet & ds, const gdcm::Tag & tag);

/** Reads the one image series (not an RT object) of \a directory; \a where names the caller in errors. */
ReferencedSeries
ReadReferencedSeries(const std::string & directory, const char * where);

/** A UID under the 2.25 root from a 128-bit hash of \a seed: the same seed, the same UID. */
std::string
DerivedUID(const std::string & seed);

/** A DS value of at most 16 characters for \a value (as many significant digits as fit). */
std::string
DecimalString(double value);

/** \a values as backslash-separated DS values. */
std::string
DecimalStrings(const double * values, std::size_t count);

/** Sets \a tag to \a value with \a vr, padded to even length (NUL for UI, space otherwise). */
void
Put(gdcm::DataSet & ds, const gdcm::Tag & tag, const gdcm::VR & vr, const std::string & value);

/** Sets \a tag to the sequence \a items (undefined lengths). */
void
PutSequence(gdcm::DataSet & ds, const gdcm::Tag & tag, const std::vector<gdcm::DataSet> & items);

/** The modules every RT object written here shares: SOP Common, Patient and General Study (copied from
 * \a series), RT Series (\a modality), Frame of Reference and General Equipment. The new SOP Instance and Series
 * UIDs are derived (DerivedUID()) from \a modality and \a contents, a text that determines the object. */
void
PutCommonModules(gdcm::DataSet &          ds,
                 const ReferencedSeries & series,
                 const std::string &      sopClassUID,
                 const std::string &      modality,
                 const std::string &      contents);

/** Writes \a ds (explicit VR little endian, with its file meta information) to a temporary name beside
 * \a path and renames it when complete. */
void
WriteDataSetAtomically(const gdcm::DataSet & ds, const std::string & path, const char * where);

// The readers' checks of the files they read (RTSTRUCT, RTDOSE).

/** \a text in double quotes. */
std::string
Quote(const std::string & text);

/** Throws naming the file: `<kind> "<path>": <message>`. */
[[noreturn]] void
FailFile(const char * where, const std::string & kind, const std::string & path, const std::string & message);

/** Refuses, naming the file, what GDCM must not see: not a file, not DICOM Part 10, or an incomplete structure. */
void
CheckDicomFile(const char * where, const std::string & kind, const std::string & path);

/** Parses \a path with \a reader (a gdcm::Reader or gdcm::ImageReader) after CheckDicomFile(); throws naming the
 * file when GDCM cannot. */
void
ReadParsedFile(gdcm::Reader & reader, const char * where, const std::string & kind, const std::string & path);

/** The numbers of the DS/IS attribute \a tag (\a count of them; when 0, at least one); throws naming the file
 * (FailFile(\a where, \a kind, \a path, ...)) when it is missing or malformed. */
std::vector<double>
FileNumbers(const gdcm::DataSet & ds,
            const gdcm::Tag &     tag,
            const std::string &   name,
            std::size_t           count,
            const char *          where,
            const std::string &   kind,
            const std::string &   path);

/** The row and column direction cosines of an Image Orientation (Patient) and their normal (row x column); false
 * unless they are two orthogonal unit vectors (to 1e-3). */
bool
OrientationAxes(const std::vector<double> & orientation,
                std::array<double, 3> &     row,
                std::array<double, 3> &     column,
                std::array<double, 3> &     normal);

/** Refuses, naming the file, a data set whose Modality (0008,0060) is not \a expected. */
void
CheckModality(const gdcm::DataSet & ds, const std::string & expected, const char * where, const std::string & path);

} // namespace dicomrt
} // namespace itk

#endif

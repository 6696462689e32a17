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
#ifndef itkDicomStructureCheck_h
#define itkDicomStructureCheck_h

#include "BiomechanicalRegistrationExport.h"

#include <string>

namespace itk {

/** \brief Refuses a corrupt DICOM Part 10 file before GDCM parses it.
 *
 * Debian's GDCM is built with assertions, and its reader aborts the process on some malformed files (a
 * truncated or overwritten File Meta Information, a truncated sequence) instead of failing. When \a path is a
 * regular file with the Part 10 preamble (128 bytes, then "DICM"), its data elements are walked without
 * interpreting their values (PS3.5 7.1, 7.5: every element, sequence and item ends inside the file and inside
 * its parent; every VR is a known one), and an itk::ExceptionObject naming \a what and \a path says what is
 * wrong. Any other file is left to the image readers.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
CheckDicomFileStructure(const std::string & path, const std::string & what);

/** \brief CheckDicomFileStructure() for every DICOM Part 10 file directly inside \a directory (GDCM's series
 * scanner parses them all), in name order; the error names the directory and the file.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationIO */
BiomechanicalRegistration_EXPORT void
CheckDicomDirectoryStructure(const std::string & directory, const std::string & what);

} // namespace itk

#endif

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
#ifndef bmrAtomicFile_h
#define bmrAtomicFile_h

#include "BiomechanicalRegistrationExport.h"

#include <string>

namespace bmr {

/** A path in the same directory as \a finalPath, hidden and unique to this
 * process, that keeps the file extension (writers choose the format by it). */
BiomechanicalRegistration_EXPORT std::string
                                 TemporaryPathFor(const std::string & finalPath);

/** Renames \a temporaryPath to \a finalPath (atomic on one file system); removes
 * the temporary file and throws itk::ExceptionObject when that fails. */
BiomechanicalRegistration_EXPORT void
CommitTemporaryFile(const std::string & temporaryPath, const std::string & finalPath);

/** Writes \a text to \a path through a temporary file. */
BiomechanicalRegistration_EXPORT void
WriteTextFileAtomically(const std::string & path, const std::string & text);

} // namespace bmr

#endif

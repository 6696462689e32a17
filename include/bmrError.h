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
#ifndef bmrError_h
#define bmrError_h

#include "BiomechanicalRegistrationExport.h"

#include <string>

namespace bmr {

/** Throws an itk::ExceptionObject carrying \a message, with the core function's
 * name as location. Every error of the numerical core goes through here so that
 * the ITK classes and the command-line tool see one exception type. */
[[noreturn]] BiomechanicalRegistration_EXPORT void
Fail(const std::string & where, const std::string & message);

/** As Fail(), for input the caller can correct (a scene entry, a grid, an image, a setting out of range): throws
 * itk::InvalidArgumentError, a subclass of itk::ExceptionObject, so that a caller may tell bad input from a failed
 * computation (the Python package raises ValueError for it, RuntimeError for the rest). */
[[noreturn]] BiomechanicalRegistration_EXPORT void
FailInput(const std::string & where, const std::string & message);

} // namespace bmr

#endif

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
#ifndef bmrTestDriverInclude_h
#define bmrTestDriverInclude_h

// Argument processing of ITK's test driver without its built-in list of every IO
// factory: the image IO this module's tests use is registered through UseITK's
// factory manager for the requested ITK components.
#include "itkTestDriverInclude.h"
#include "bmrNumerics.h"

// The driver is a program and configures its process as biomechreg does (bmr::ConfigureNumerics()), so that the
// tests' numbers are the CLI's; bmrLinearElasticModelTest checks that the library itself leaves the BLAS alone.
inline int
ProcessArgumentsOnly(int * ac, ArgumentStringType * av)
{
  bmr::ConfigureNumerics();
  return ProcessArguments(ac, av);
}

#endif

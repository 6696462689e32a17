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
#include "bmrError.h"

#include "itkMacro.h"

namespace bmr {

void
Fail(const std::string & where, const std::string & message)
{
  throw itk::ExceptionObject(__FILE__, __LINE__, message, where);
}

void
FailInput(const std::string & where, const std::string & message)
{
  throw itk::InvalidArgumentError(__FILE__, __LINE__, message, where);
}

} // namespace bmr

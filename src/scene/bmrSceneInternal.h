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
// Helpers shared by the scene sources (bmrScene.cxx, bmrSceneParse.cxx): not part of the public API.
#ifndef bmrSceneInternal_h
#define bmrSceneInternal_h

#include "bmrError.h"

#include <string>

namespace bmr::detail {

/** Fails with the scene's source, the entry at fault and what is wrong with it. */
[[noreturn]] inline void
SceneError(const std::string & source, const std::string & entry, const std::string & message)
{
  FailInput("Scene", source + ": " + entry + ": " + message);
}

} // namespace bmr::detail

#endif // bmrSceneInternal_h

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
#ifndef bmrRuntimeSetting_h
#define bmrRuntimeSetting_h

// A process setting of a runtime library found at run time (private to src/).
#include <dlfcn.h>

namespace bmr {

/** The getter and setter of an integer setting of a library the process may or may not have loaded (OpenBLAS's
 * threads, the OpenMP runtime's active levels), looked up by name at run time so that the library works unchanged
 * without it: both null unless both are found. */
struct RuntimeIntSetting
{
  int (*get)(){ nullptr };
  void (*set)(int){ nullptr };
};

inline RuntimeIntSetting
FindRuntimeIntSetting(const char * getter, const char * setter)
{
  RuntimeIntSetting s;
  s.get = reinterpret_cast<int (*)()>(dlsym(RTLD_DEFAULT, getter));
  s.set = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, setter));
  return s.get && s.set ? s : RuntimeIntSetting{};
}

} // namespace bmr

#endif

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
// The program's malloc. biomechreg (never the library, which leaves its host's malloc alone) links jemalloc where
// it is installed and asks it for transparent huge pages: on virtual machines every 4 KiB page fault can cost
// microseconds, and meshing, assembly and the rescans fault in gigabytes, while the system grants huge pages only
// to memory that asks for them ("madvise", the usual setting). glibc's malloc asks only when GLIBC_TUNABLES says
// so at start-up, which would need the program to restart itself; jemalloc reads its settings from the program's
// own malloc_conf when it starts. The results do not depend on the allocator (docs/history/benchmarks.md, "The
// program's malloc").
#include "biomechregCommon.h"

#include <string>

#ifdef BMR_JEMALLOC
#  include <jemalloc/jemalloc.h>

// jemalloc's documented hook: read when it initializes, before main (the library's default is a weak symbol).
extern "C" {
const char * malloc_conf = "thp:always,metadata_thp:auto"; // NOLINT: the name jemalloc looks for
}
#endif

namespace bmrcli {
std::string
MallocDescription()
{
#ifdef BMR_JEMALLOC
  const char * thp = nullptr;
  std::size_t  size = sizeof(thp);
  if (mallctl("opt.thp", static_cast<void *>(&thp), &size, nullptr, 0) == 0 && thp != nullptr)
  {
    return std::string("jemalloc (transparent huge pages: ") + thp + ")";
  }
  return "jemalloc";
#else
  return "the C library's (no huge pages requested)";
#endif
}
} // namespace bmrcli

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
#include "bmrMemoryWarmUp.h"

#include <cstring>
#include <vector>

#if defined(__unix__) || defined(__APPLE__)
#  include <sys/mman.h>
#  define BMR_HAVE_MMAP 1
#endif

namespace bmr {

namespace {
// Chunks of 32 MiB: Close() waits at most one chunk's writes before the release.
constexpr std::size_t ChunkBytes = std::size_t{ 32 } << 20;
} // namespace

MemoryWarmUp::MemoryWarmUp(std::size_t capBytes)
  : m_Cap(capBytes)
{}

MemoryWarmUp::~MemoryWarmUp()
{
  Close();
}

/** Claims the warming for this thread (and, with \a holding, the wait for Close()); false when closed or taken. */
bool
MemoryWarmUp::Begin(bool holding)
{
#if defined(BMR_HAVE_MMAP)
  const std::lock_guard<std::mutex> lock(m_Mutex);
  if (m_Closed || m_Warming || m_Holding)
  {
    return false;
  }
  m_Warming = true;
  m_Holding = holding;
  return true;
#else
  (void)holding;
  return false;
#endif
}

std::size_t
MemoryWarmUp::WarmWhile(const std::function<bool()> & more)
{
  return Begin(false) ? WriteChunks(more) : 0;
}

std::size_t
MemoryWarmUp::WarmWhileOpen()
{
  if (!Begin(true))
  {
    return 0;
  }
  const std::size_t held = WriteChunks({});
  // Held until Close() releases it: memory released long before the allocation would be handed back to the host.
  std::unique_lock<std::mutex> lock(m_Mutex);
  m_Changed.wait(lock, [this] { return m_Closed; });
  m_Holding = false;
  return held;
}

/** Writes chunks while open, under the cap and \a more() (if given) holds; ends the claim of Begin(). */
std::size_t
MemoryWarmUp::WriteChunks(const std::function<bool()> & more)
{
#if defined(BMR_HAVE_MMAP)
  // Mapped directly rather than through malloc, so that every chunk is fresh memory and is returned to the
  // system (not kept in a malloc arena) when released.
  while (m_Held.load() + ChunkBytes <= m_Cap && !IsClosed() && (!more || more()))
  {
    void * chunk = mmap(nullptr, ChunkBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (chunk == MAP_FAILED)
    {
      break; // out of address space or memory: warm no further
    }
#  if defined(MADV_HUGEPAGE)
    madvise(chunk, ChunkBytes, MADV_HUGEPAGE); // as malloc's large blocks get them (glibc.malloc.hugetlb=1)
#  endif
    std::memset(chunk, 0, ChunkBytes);
    const std::lock_guard<std::mutex> lock(m_Mutex);
    m_Chunks.push_back(chunk);
    m_Held.store(m_Held.load() + ChunkBytes);
  }
#else
  (void)more;
#endif
  std::size_t held = 0;
  {
    const std::lock_guard<std::mutex> lock(m_Mutex);
    held = m_Held.load(); // before Close(), waiting for this, releases it
    m_Warming = false;
  }
  m_Changed.notify_all();
  return held;
}

void
MemoryWarmUp::Close()
{
  std::unique_lock<std::mutex> lock(m_Mutex);
  m_Closed = true;
  m_Changed.notify_all();
  m_Changed.wait(lock, [this] { return !m_Warming; });
#if defined(BMR_HAVE_MMAP)
  for (void * chunk : m_Chunks)
  {
    munmap(chunk, ChunkBytes);
  }
#endif
  m_Chunks.clear();
  m_Held.store(0);
}

bool
MemoryWarmUp::IsClosed() const
{
  const std::lock_guard<std::mutex> lock(m_Mutex);
  return m_Closed;
}

} // namespace bmr

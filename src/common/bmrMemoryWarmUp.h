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
#ifndef bmrMemoryWarmUp_h
#define bmrMemoryWarmUp_h

#include "BiomechanicalRegistrationExport.h"

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <vector>

namespace bmr {

/** \brief Faults fresh memory in on an idle thread for a large allocation that another thread is about to make.
 *
 * On a virtual machine that hands freed memory back to its host (free page reporting), the first write to a page
 * the process has not used costs far more than the write itself (about a hundredfold). Memory a process releases
 * stays with the guest for a while before it is reported, and is cheap to fault in again. The estimation's first
 * fine factorization writes a new factor of a few hundred MiB while the main thread waits for it; warmed by the
 * waiting thread, that factorization is faster (measurements: docs/estimation.md).
 *
 * WarmWhileOpen() (on the idle thread) writes fresh memory chunk by chunk until Close() is called or the cap is
 * reached and holds it until Close(); Close() (on the thread about to allocate) stops the warming and returns once
 * the memory is released, so that its allocation finds those pages. After Close(), WarmWhileOpen() does nothing. Every
 * WarmWhileOpen() must be matched by a Close() from another thread (the destructor closes too), or it waits forever.
 * The warming only changes where page faults are paid, never a result. Elsewhere (bare metal) a fault costs little and
 * the idle thread's work is wasted but harmless; on systems without mmap it does nothing. */
class BiomechanicalRegistration_EXPORT MemoryWarmUp
{
public:
  /** \a capBytes: the most memory held at once [bytes]. */
  explicit MemoryWarmUp(std::size_t capBytes);
  ~MemoryWarmUp();
  MemoryWarmUp(const MemoryWarmUp &) = delete;
  MemoryWarmUp &
  operator=(const MemoryWarmUp &) = delete;

  /** Writes fresh memory until Close() or the cap, holds it until Close() releases it and returns how many bytes
   * are held then, counting those an earlier WarmWhile() wrote (0 at once when already closed, when another thread
   * is warming or holding, or when this platform has no mmap). */
  std::size_t
  WarmWhileOpen();

  /** As WarmWhileOpen(), but also stops, before each 32 MiB chunk, once \a more() is false, and returns at once
   * with the memory still held (for a later WarmWhileOpen() to add to, and for Close() to release): a thread that
   * waits for two things in turn warms during the first, does its own work, and warms again during the second.
   * Returns the bytes held (0 as WarmWhileOpen()). */
  std::size_t
  WarmWhile(const std::function<bool()> & more);

  /** Stops the warming, releases its memory (once the chunk being written is done), and keeps any later warming
   * from starting. */
  void
  Close();

  bool
  IsClosed() const;

  /** Bytes written and held by the warming in progress (0 before it starts and after its release). */
  std::size_t
  GetHeldBytes() const
  {
    return m_Held.load();
  }

private:
  const std::size_t        m_Cap;
  mutable std::mutex       m_Mutex;
  std::condition_variable  m_Changed; // closed, or the warmed memory released
  bool                     m_Closed{ false };
  bool                     m_Warming{ false }; // a thread is writing chunks
  bool                     m_Holding{ false }; // a WarmWhileOpen() waits for Close()
  std::vector<void *>      m_Chunks;           // written and held until Close()
  std::atomic<std::size_t> m_Held{ 0 };

  bool
  Begin(bool holding);
  std::size_t
  WriteChunks(const std::function<bool()> & more);
};

} // namespace bmr

#endif

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
#ifndef bmrNumerics_h
#define bmrNumerics_h

#include "BiomechanicalRegistrationExport.h"

namespace bmr {
/** \brief Process-wide numerical settings that a program may choose for the library.
 *
 * No library call changes the process it runs in: the library is a guest in 3D Slicer, a Python interpreter or
 * someone's ITK application, whose BLAS and malloc belong to the host. What the library would like from its
 * host is collected here, and only ConfigureNumerics() applies it, when the program (biomechreg, a test driver,
 * a user's main) asks.
 *
 * The BLAS. The sparse factorizations call the BLAS (level 3) under CHOLMOD's analysis. A multithreaded
 * OpenBLAS partitions those calls by its own thread count and so rounds them differently on machines with
 * different core counts; with one BLAS thread the factors, and every field and estimate, are the same bits on
 * any machine and for any number of the library's own threads (the library parallelizes over parts of the
 * elimination tree instead, in a decomposition that does not depend on the thread count). Without the call the
 * results are as accurate, and the same bits run to run for one BLAS configuration, but may differ in the last
 * bits between hosts whose BLAS runs a different number of threads.
 */
struct NumericsConfiguration
{
  /** OpenBLAS's thread count (found at run time; any other BLAS is left alone). 1: results independent of the
   * machine (above); 0: left as the host set it. */
  int blasThreads{ 1 };
};

/** What ConfigureNumerics() found and did. */
struct NumericsState
{
  bool openBlas{ false }; ///< an OpenBLAS is loaded (its thread setter was found)
  int  blasThreads{ -1 }; ///< OpenBLAS's thread count after the call; -1 without OpenBLAS
};

/** Applies \a configuration to the whole process (see NumericsConfiguration): call it once, early, from the
 * program's main, before other threads use the BLAS. biomechreg calls it with the defaults. Throws
 * itk::ExceptionObject for a negative thread count. */
BiomechanicalRegistration_EXPORT NumericsState
ConfigureNumerics(const NumericsConfiguration & configuration = NumericsConfiguration());

/** The BLAS's thread count as it is now (read only): OpenBLAS's, or -1 when the BLAS is not OpenBLAS. */
BiomechanicalRegistration_EXPORT int
BlasThreads();
} // namespace bmr

#endif

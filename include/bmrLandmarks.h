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
#ifndef bmrLandmarks_h
#define bmrLandmarks_h

#include "BiomechanicalRegistrationExport.h"

#include <array>
#include <string>
#include <vector>

namespace bmr {

/** \brief A named point in patient LPS physical coordinates [mm].
 *
 * LPS is ITK's convention (x towards the patient's left, y posterior, z superior), the same space as
 * an itk::Image's physical points. 3D Slicer works in RAS (x right→left negated, y anterior): the
 * readers and writers below convert where a file declares RAS. */
struct BiomechanicalRegistration_EXPORT Landmark
{
  std::string           id;
  std::array<double, 3> point{ { 0, 0, 0 } }; ///< LPS mm
};

/** Reads landmarks by the file's extension:
 * - `.csv`: a header `id,x_mm,y_mm,z_mm` (LPS mm), '#' comment lines allowed;
 * - `.fcsv`: 3D Slicer fiducial list; coordinates are RAS unless the header says
 *   `# CoordinateSystem = LPS` (or `= 1`, the older numeric form);
 * - `.json`: 3D Slicer markups (`markups[].controlPoints[].position`), in the list's
 *   `coordinateSystem` (RAS when absent).
 * Throws itk::ExceptionObject naming the file and line on any malformed entry, a non-finite
 * coordinate, a duplicate id, or an empty list. */
BiomechanicalRegistration_EXPORT std::vector<Landmark>
                                 ReadLandmarks(const std::string & path);

/** Writes \a landmarks (LPS mm) in the format chosen by the extension of \a path (as ReadLandmarks;
 * `.fcsv` and `.json` are written in LPS and say so), through a temporary file renamed when complete. */
BiomechanicalRegistration_EXPORT void
WriteLandmarks(const std::string & path, const std::vector<Landmark> & landmarks);

/** Pairs two landmark sets of the same objects seen in two scans (e.g. implanted seeds detected in the
 * moving and in the fixed CT). Returns, for every landmark of \a a, the index of its partner in \a b:
 * the assignment that minimizes the sum of squared distances after the translation between the two
 * centroids is removed (organ motion between scans is mostly a translation). Exhaustive for up to 8
 * landmarks, greedy nearest pairs beyond. Throws when the two sets differ in size or are empty. */
BiomechanicalRegistration_EXPORT std::vector<std::size_t>
                                 MatchLandmarks(const std::vector<Landmark> & a, const std::vector<Landmark> & b);

} // namespace bmr

#endif

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
#ifndef bmrVtuWriter_h
#define bmrVtuWriter_h

#include "bmrTetrahedralMesh.h"

namespace bmr {

/** A named data array: \c components values per point or per cell. */
struct BiomechanicalRegistration_EXPORT DataArray
{
  std::string         name;
  int                 components{ 1 };
  std::vector<double> values;
};

/** Writes the tetrahedra of \a mesh with point and cell data as a VTK XML
 * unstructured grid (.vtu, readable by ParaView and 3D Slicer), through a
 * temporary file so that the file is complete or absent. Coordinates in LPS mm. */
BiomechanicalRegistration_EXPORT void
WriteVtu(const std::string &            fileName,
         const TetrahedralMesh &        mesh,
         const std::vector<DataArray> & pointData,
         const std::vector<DataArray> & cellData);

} // namespace bmr

#endif

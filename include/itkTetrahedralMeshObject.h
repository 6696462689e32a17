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
#ifndef itkTetrahedralMeshObject_h
#define itkTetrahedralMeshObject_h

#include "bmrTetrahedralMesh.h"
#include "itkGridGeometryConversion.h"
#include "itkSimpleDataObjectDecorator.h"

#include <ostream>

namespace bmr {
/** Summary for PrintSelf: node, element and boundary-face counts. */
inline std::ostream &
operator<<(std::ostream & os, const TetrahedralMesh & mesh)
{
  return os << mesh.GetNumberOfPoints() << " nodes, " << mesh.GetNumberOfTetrahedra() << " tetrahedra, "
            << mesh.boundaryFaceLabels.size() << " boundary faces"
            << (mesh.displacement.empty() ? "" : ", with displacement");
}
/** Exact equality of every array (SimpleDataObjectDecorator::Set() uses it to decide whether to call Modified()). */
inline bool
operator==(const TetrahedralMesh & a, const TetrahedralMesh & b)
{
  return a.points == b.points && a.tetrahedra == b.tetrahedra && a.labels == b.labels &&
         a.boundaryFaces == b.boundaryFaces && a.boundaryFaceLabels == b.boundaryFaceLabels &&
         a.displacement == b.displacement && a.force == b.force;
}
inline bool
operator!=(const TetrahedralMesh & a, const TetrahedralMesh & b)
{
  return !(a == b);
}
} // namespace bmr

namespace itk {
/** \brief Pipeline data object holding a labeled tetrahedral mesh (bmr::TetrahedralMesh).
 *
 * Coordinates in LPS mm; optional nodal displacement [mm] and force [mN].
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationMesh
 */
using TetrahedralMeshObject = SimpleDataObjectDecorator<bmr::TetrahedralMesh>;

} // namespace itk

#endif

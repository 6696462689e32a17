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
#include "bmrGridGeometry.h"
#include "itkImageBase.h"
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
/** \brief Pipeline data object holding a labelled tetrahedral mesh (bmr::TetrahedralMesh).
 *
 * Coordinates in LPS mm; optional nodal displacement [mm] and force [mN].
 * \ingroup BiomechanicalRegistration
 */
using TetrahedralMeshObject = SimpleDataObjectDecorator<bmr::TetrahedralMesh>;

/** Geometry of the largest possible region of an ITK image, 0-based: the origin
 * is the physical point of the region's start index. */
inline bmr::GridGeometry
GridGeometryOf(const ImageBase<3> * image)
{
  bmr::GridGeometry                g;
  const auto                       region = image->GetLargestPossibleRegion();
  typename ImageBase<3>::PointType origin;
  image->TransformIndexToPhysicalPoint(region.GetIndex(), origin);
  for (unsigned int i = 0; i < 3; ++i)
  {
    g.size[i] = region.GetSize(i);
    g.origin[i] = origin[i];
    g.spacing[i] = image->GetSpacing()[i];
    for (unsigned int j = 0; j < 3; ++j)
    {
      g.direction[3 * i + j] = image->GetDirection()(i, j);
    }
  }
  return g;
}
} // namespace itk

#endif

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
#ifndef bmrDisplacementFieldRasterizer_h
#define bmrDisplacementFieldRasterizer_h

#include "bmrGridGeometry.h"
#include "bmrTetrahedralMesh.h"

#include <iosfwd>

namespace itk {
class MultiThreaderBase;
}

namespace bmr {

/** Which map of the finite-element deformation a field represents.
 *
 * The FE map is phi(X) = X + u(X), piecewise linear on the undeformed mesh.
 * Push: d(X) = u(X) on a moving-space grid (moving -> fixed).
 * PullBack: d(x) = phi^{-1}(x) - x on a fixed-space grid (fixed -> moving, the
 * ITK convention of DisplacementFieldTransform): x is located in the deformed
 * element, and its barycentric coordinates combine the undeformed positions,
 * which is the exact inverse of the piecewise-linear map. */
enum class FieldKindEnum
{
  Push,
  PullBack
};
BiomechanicalRegistration_EXPORT std::ostream &
                                 operator<<(std::ostream & os, FieldKindEnum value);

/** \brief Evaluates the FE displacement on the voxels of a grid covered by the mesh.
 *
 * Each element is scan-converted over its bounding box: every voxel center
 * inside the element (barycentric coordinates >= -1e-10) gets the barycentric
 * interpolation. Along a row of the box the barycentric coordinates are affine
 * in the voxel index, so the run of candidate voxels is bounded analytically
 * (with a margin) and only that run is tested, with the same test and
 * arithmetic as a scan of the whole box: the output is that of the full scan,
 * bit for bit. A voxel on a shared face belongs to the element of lowest
 * index, so a region gives the same values whatever the split of the grid into
 * regions (threads). Elements inverted by the deformation have no unique
 * inverse and are skipped for PullBack (counted in GetNumberOfInvertedElements()).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationField
 */
class BiomechanicalRegistration_EXPORT DisplacementFieldRasterizer
{
public:
  /** \a displacement is 3N [mm]; \a grid is 0-based (region start at index 0). */
  DisplacementFieldRasterizer(const TetrahedralMesh &     mesh,
                              const std::vector<double> & displacement,
                              const GridGeometry &        grid,
                              FieldKindEnum               kind);

  /** Writes the voxels of the region [start, start+size) of whole-grid buffers:
   * \a field (3 doubles per voxel, LPS mm) and \a inside (1 where covered, else
   * left untouched: clear it to 0 first). Thread safe for disjoint regions. */
  void
  RasterizeRegion(const std::array<std::size_t, 3> & start,
                  const std::array<std::size_t, 3> & size,
                  double *                           field,
                  unsigned char *                    inside) const;

  std::size_t
  GetNumberOfInvertedElements() const
  {
    return m_Inverted;
  }

private:
  struct Element
  {
    double       v0[3];        // first vertex, continuous index
    double       inv[9];       // inverse of [v1-v0, v2-v0, v3-v0] (row-major)
    std::int64_t lo[3], hi[3]; // voxel bounding box (inclusive)
    std::int32_t nodes[4];
    double       bound[4][3]; // t = i - v0[0] on the row (j, k): t >= (side 1) or <= (side -1)
    std::int8_t  side[4];     // bound[r][0] + bound[r][1] (j - v0[1]) + bound[r][2] (k - v0[2]); 0: none
  };

  /** The row bounds of \a el (bound, side) from its inverse and box. */
  static void
  ComputeRowBounds(Element & el);

  /** The voxels [first, last] of the row at (j, k) - v0 = (dy, dz) within [lo, hi] along x that may lie
   * in \a el: a superset of those the exact barycentric test accepts; false when there is none. */
  static bool
  RowRun(const Element & el,
         double          dy,
         double          dz,
         std::int64_t    lo,
         std::int64_t    hi,
         std::int64_t &  first,
         std::int64_t &  last);

  const TetrahedralMesh &     m_Mesh;
  const std::vector<double> & m_Displacement;
  GridGeometry                m_Grid;
  FieldKindEnum               m_Kind;
  std::vector<Element>        m_Elements;
  std::size_t                 m_Inverted{ 0 };
  double                      m_IndexToPoint[9]; // direction x diag(spacing), as GridGeometry::IndexToPoint
};

/** \brief Fills the voxels not covered by the mesh with a continuous extension.
 *
 * Solves Laplace's equation (anisotropic 7-point stencil, physical spacing) on a
 * grid coarsened by \a coarsening, with the covered voxels' mean as Dirichlet
 * value at each coarse node whose neighborhood touches the mesh and 0 on the
 * border of the grid, then interpolates the coarse solution trilinearly into
 * every uncovered fine voxel. Hollow organs (lumens) thus get the harmonic
 * interpolation of their wall motion, bone interiors (enclosed by u = 0) get
 * ~0, and the field decays to zero towards the image border. Then about 2.4 w sweeps (24 for the default
 * coarsening 4) of successive over-relaxation (Gauss-Seidel, each update scaled by omega = 1.7) of the fine-grid
 * Laplacian on the uncovered voxels within w = 2 coarsening + 2 voxels (city-block distance, w capped at
 * 65534) of the mesh remove the coarse interpolation's mismatch at the mesh boundary:
 * \f$ v \leftarrow (1 - \omega) v + \omega \sum_d h_d^{-2} (v_{-d} + v_{+d}) / \sum_d 2 h_d^{-2} \f$.
 *
 * Threaded on \a threader's work units when given (else sequential): the coarse components are solved
 * as independent tasks, the interpolation and the band search split by planes, and the over-relaxation
 * sweeps pipelined plane by plane so that every update sees the values of the sequential order. The
 * result is bit-identical for any number of threads (fixed sweep and summation orders). */
BiomechanicalRegistration_EXPORT void
FillOutsideHarmonic(const GridGeometry &     grid,
                    double *                 field,
                    const unsigned char *    inside,
                    unsigned int             coarsening,
                    itk::MultiThreaderBase * threader = nullptr);

/** Advises the kernel to back the whole 2 MiB blocks of a buffer not yet written with transparent huge
 * pages (Linux, where THP is "madvise" by default; elsewhere nothing). A hint only: values are unaffected.
 * Why: a field is hundreds of MB, and on a virtual machine faulting it in 4 KiB pages can cost more than the
 * rasterization itself. */
BiomechanicalRegistration_EXPORT void
AdviseHugePages(void * data, std::size_t bytes);

/** \brief Finds the element containing a point of a tetrahedral mesh (bucket grid).
 * \ingroup BiomechanicalRegistration */
class BiomechanicalRegistration_EXPORT PointLocator
{
public:
  /** \a points is 3N (positions the elements are located in, e.g. deformed), \a tetrahedra 4M. */
  PointLocator(const std::vector<double> & points, const std::vector<std::int32_t> & tetrahedra);

  /** Returns the lowest-index element containing \a p (tolerance \a tolerance in
   * barycentric coordinates) with its barycentric coordinates, or -1. */
  std::int64_t
  Locate(const std::array<double, 3> & p, std::array<double, 4> & barycentric, double tolerance = 1e-10) const;

private:
  bool
  Barycentric(std::size_t e, const std::array<double, 3> & p, std::array<double, 4> & b) const;

  const std::vector<double> &       m_Points;
  const std::vector<std::int32_t> & m_Tetrahedra;
  std::array<double, 3>             m_Lower{};
  std::array<double, 3>             m_CellSize{};
  std::array<std::size_t, 3>        m_Cells{};
  std::vector<std::size_t>          m_CellStart;
  std::vector<std::int32_t>         m_CellElements;
};

/** FE displacement u(X) [mm] at an undeformed (moving-space) point X, located with a
 * PointLocator built on the undeformed nodes; returns false when X is outside the mesh. */
BiomechanicalRegistration_EXPORT bool
InterpolateDisplacement(const PointLocator &          undeformedLocator,
                        const TetrahedralMesh &       mesh,
                        const std::vector<double> &   displacement,
                        const std::array<double, 3> & X,
                        std::array<double, 3> &       u);

} // namespace bmr

#endif

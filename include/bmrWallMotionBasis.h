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
#ifndef bmrWallMotionBasis_h
#define bmrWallMotionBasis_h

#include "bmrLoadParameterization.h"

#include <array>
#include <string>
#include <vector>

namespace bmr {

/** \brief A basis of wall motion learned from examples (dissertation ch. 5, section 5.3.2.2): the mean and the
 * principal modes of the loaded walls' displacements on a reference surface, the atlas.
 *
 * The atlas is the walls' surface the examples were measured on: its points [mm], the wall each point belongs to,
 * and its triangles (point indices), through which the basis is carried to another mesh of the walls
 * (TransferWallMotionBasis()). An example is the displacement [mm] of every atlas point (3 values per point, x y z),
 * e.g. surface matching of the moving walls to a daily scan's organs. With the examples \f$ x_i \f$ (i = 1..m) as
 * columns and their mean \f$ \mu \f$, the centred matrix \f$ X - \mu 1^T = U \Sigma V^T \f$ (thin SVD) gives
 * the modes \f$ \psi_k = U_{:,k} \f$ (orthonormal), their variances \f$ \lambda_k = \sigma_k^2 / (m - 1) \f$
 * [mm^2] and the explained variance \f$ \sum_{j \le k} \lambda_j / \sum_j \lambda_j \f$. A wall motion in the basis is
 * \f$ d = \mu + \sum_k p_k \psi_k \f$ with the prior \f$ \tfrac{w}{2} \sum_k p_k^2 / \lambda_k \f$ (TrainedWallLoads).
 *
 * File format (WriteWallMotionBasis(), ReadWallMotionBasis()): JSON, {"format": "biomechreg-wall-motion-basis",
 * "version": 1, "units": {"points": "mm", "mean": "mm", "modes": "mm per unit p", "variances": "mm^2"},
 * "walls": [names], "points": [[x, y, z]...], "point_walls": [wall index per point], "triangles": [[i, j, k]...],
 * "mean": [3 per point], "modes": [[3 per point]...], "variances": [...], "explained_variance": [...],
 * "examples": m, "training": "what it was trained on (a fingerprint of the inputs)"}.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
struct BiomechanicalRegistration_EXPORT WallMotionBasis
{
  std::vector<std::string>                 walls;             ///< the loaded walls' names (the scene's force surfaces)
  std::vector<std::array<double, 3>>       points;            ///< atlas points [mm]
  std::vector<std::int32_t>                pointWalls;        ///< index into walls, per point
  std::vector<std::array<std::int32_t, 3>> triangles;         ///< atlas triangles (point indices), each on one wall
  std::vector<double>                      mean;              ///< mean displacement [mm], 3 per point
  std::vector<std::vector<double>>         modes;             ///< orthonormal modes, 3 per point each, by variance
  std::vector<double>                      variances;         ///< [mm^2], per mode, decreasing
  std::vector<double>                      explainedVariance; ///< cumulative fraction, per mode
  std::size_t                              examples{ 0 };
  std::string                              training; ///< what it was trained on

  std::size_t
  GetNumberOfModes() const
  {
    return modes.size();
  }
  /** Throws itk::InvalidArgumentError (bmr::FailInput) when the sizes disagree, an index is out of range, a value is
   * not finite or a variance is not positive. */
  void
  Validate() const;
};

/** The atlas of a mesh's loaded walls: the points of \a walls' nodes (in the order of \a walls, a node on two walls
 * once, on the first) and the boundary faces of each wall's face label whose three nodes lie on that wall; \a nodes
 * (optional) gets each point's mesh node. */
BiomechanicalRegistration_EXPORT WallMotionBasis
WallAtlas(const TetrahedralMesh &         mesh,
          const std::vector<LoadedWall> & walls,
          std::vector<std::int32_t> *     nodes = nullptr);

/** PCA of \a examples (each 3 values per point of \a atlas, whose points, walls and triangles are kept) into at most
 * \a maximumModes modes (fewer when the examples span fewer: modes of variance below 1e-12 of the largest are
 * dropped). \a training says what the examples came from. Throws for fewer than two examples or a wrong size. */
BiomechanicalRegistration_EXPORT WallMotionBasis
TrainWallMotionBasis(WallMotionBasis                          atlas,
                     const std::vector<std::vector<double>> & examples,
                     std::size_t                              maximumModes,
                     const std::string &                      training);

/** Writes \a basis to \a path (JSON, through a temporary file; see WallMotionBasis). */
BiomechanicalRegistration_EXPORT void
WriteWallMotionBasis(const WallMotionBasis & basis, const std::string & path);
/** Reads and validates a basis written by WriteWallMotionBasis(); throws naming \a path when it cannot. */
BiomechanicalRegistration_EXPORT WallMotionBasis
ReadWallMotionBasis(const std::string & path);

/** The atlas of \a basis fitted to another mesh's walls \a walls (WallAtlas() of that mesh; the same walls by name, in
 * the same order), dissertation section 5.3.2.3: per wall, the atlas moved so that its centroid is the wall's, then
 * \a iterations rounds in which every atlas point moves towards its closest point on the wall, each move averaged with
 * those of the point's neighbours on the atlas triangles (so that the atlas slides on as a sheet instead of bunching
 * at the nearest nodes), and a last projection onto the wall. Few rounds: repeated, the averaged moves also slide
 * the points along the wall, away from their correspondents (bmrWallMotionBasisTest measures both).
 */
BiomechanicalRegistration_EXPORT std::vector<double>
FitAtlasToWalls(const WallMotionBasis & basis, const WallMotionBasis & walls, unsigned int iterations = 3);

/** The first \a modes modes of \a basis at other points of the same walls: each point \a points[i] (3 per point) of
 * wall \a pointWalls[i] (index into basis.walls) is projected onto the closest atlas triangle of its wall, whose
 * corners' values it takes barycentrically. mean and modes as in WallMotionBasis, at the new points;
 * \a distances [mm], per point, how far it lay from the atlas surface. With \a fittedAtlas (FitAtlasToWalls() of
 * the points' walls), the points are located on the atlas where it was fitted, the values still the basis's: another
 * patient's walls take the basis through the correspondence. */
struct BiomechanicalRegistration_EXPORT TransferredWallBasis
{
  std::vector<double>              mean;
  std::vector<std::vector<double>> modes;
  std::vector<double>              variances;
  std::vector<double>              distances;
};
BiomechanicalRegistration_EXPORT TransferredWallBasis
TransferWallMotionBasis(const WallMotionBasis &           basis,
                        std::size_t                       modes,
                        const std::vector<double> &       points,
                        const std::vector<std::int32_t> & pointWalls,
                        const std::vector<double> *       fittedAtlas = nullptr);

} // namespace bmr

#endif

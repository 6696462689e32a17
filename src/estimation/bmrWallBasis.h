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
#ifndef bmrWallBasis_h
#define bmrWallBasis_h

#include "BiomechanicalRegistrationExport.h"

#include <array>
#include <cstdint>
#include <vector>

namespace bmr {

/** \brief A smooth, reduced basis for the displacement of the loaded walls.
 *
 * Control points are picked on every wall by farthest-point sampling (start:
 * the node farthest from the wall's centroid; then the node farthest from every
 * point picked so far, until no node is farther than \c spacing [mm]), and the
 * displacement of wall node k is the normalized Gaussian blend of the control
 * displacements c_j of its own wall:
 * \f[ d_k = \sum_j W_{kj} c_j, \qquad
 *     W_{kj} = \frac{\exp(-|x_k - p_j|^2 / 2\sigma^2)}{\sum_i \exp(-|x_k - p_i|^2 / 2\sigma^2)},
 *     \quad \sigma = \mathrm{spacing}. \f]
 * The weights sum to one, so rigid translations of a wall are represented
 * exactly; wiggles shorter than the spacing are not representable. That is the
 * point: with one free displacement per wall node, tangential sliding (which a
 * distance objective does not see) can shape the organ surfaces locally for
 * any modulus and makes E unidentifiable (dissertation chapter 5 reduces the
 * force space for the same reason, with a PCA basis).
 * Weights below 1e-4 of a node's largest are dropped. The parameters are not
 * the control displacements c themselves but q = L^T c, with L L^T = W^T W the
 * Cholesky factor of the Gram matrix: the columns of W L^{-T} are orthonormal,
 * so overlapping Gaussians do not make the optimization ill-conditioned.
 * Deterministic.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT WallBasis
{
public:
  /** \a points: 3N mesh coordinates [mm]; \a walls: for each wall, the indices
   * (into the parameter-node list of size \a numberOfNodes) and mesh node ids of
   * its nodes; a node may belong to several walls (it then blends all their
   * control points). spacing <= 0 gives the identity basis (one control per node); spacing = +infinity one
   * control point per wall, every node of which it weighs 1 (a uniform value per wall). */
  WallBasis(const std::vector<double> &                                             points,
            const std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> & walls,
            std::size_t                                                             numberOfNodes,
            double                                                                  spacing);

  /** Number of control points (3 parameters each). */
  std::size_t
  GetNumberOfControlPoints() const
  {
    return m_NumberOfControlPoints;
  }
  /** d = W L^{-T} q (3 per node from 3 per control point). */
  std::vector<double>
  Expand(const std::vector<double> & c) const;
  /** L^{-1} W^T g, the gradient with respect to q of a function of d with gradient g. */
  std::vector<double>
  ExpandTranspose(const std::vector<double> & g) const;
  /** Least-squares fit q = argmin |W L^{-T} q - d|^2 = L^{-1} W^T d. */
  std::vector<double>
  Fit(const std::vector<double> & d) const;

private:
  struct Entry
  {
    std::int32_t control;
    double       weight;
  };
  bool                            m_Identity{ false };
  std::size_t                     m_NumberOfNodes{ 0 };
  std::size_t                     m_NumberOfControlPoints{ 0 };
  std::vector<std::vector<Entry>> m_Rows;     ///< per node
  std::vector<double>             m_Cholesky; ///< lower factor of W^T W (+ ridge), row-major
  void
  SolveLower(std::vector<double> & x) const; ///< x <- L^{-1} x, per component
  void
  SolveUpper(std::vector<double> & x) const; ///< x <- L^{-T} x, per component
};

} // namespace bmr

#endif

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
#ifndef bmrTrainedWallLoads_h
#define bmrTrainedWallLoads_h

#include "bmrWallMotionBasis.h"

#include <memory>

namespace bmr {

/** \brief Unknown wall motions in a basis learned from examples (dissertation ch. 5): the loaded walls' nodes are
 * prescribed \f$ d = \bar\mu + \sum_{k<K} p_k \bar\psi_k \f$, with \f$ \bar\mu, \bar\psi_k \f$ a WallMotionBasis's mean
 * and first K modes carried to this mesh's wall nodes through the atlas fitted to its walls (FitAtlasToWalls(),
 * TransferWallMotionBasis()), and the prior
 * \f$ R(p) = \tfrac{w}{2} \sum_k p_k^2 / \lambda_k \f$ with the modes' variances \f$ \lambda_k \f$ [mm^2].
 *
 * The prior is the Gaussian the training examples describe; with the surface distances' noise \f$ \sigma \f$ [mm],
 * \f$ \Phi + R \f$ is \f$ \sigma^2 \f$ times the negative log posterior for \f$ w = \sigma^2 \f$
 * (WallLoadSettings::basisPriorWeight, default 0.25 mm^2: half-millimetre surface noise). Held nodes keep their values
 * and forces do not depend on p, as in WallLoads; a wall node that is also held is not a control node.
 * IsReducedBasis(): the estimator solves the inner problem by Levenberg-Marquardt.
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEstimation
 */
class BiomechanicalRegistration_EXPORT TrainedWallLoads : public LoadParameterization
{
public:
  /** \a heldNodes, \a heldValues, \a forces as WallLoads; \a walls the scene's loaded walls on \a mesh, each of which
   * \a basis must have (by name); \a modes of its modes (0: all), \a priorWeight w [mm^2]. Throws naming what is
   * wrong. \a mesh must outlive the object. */
  TrainedWallLoads(const TetrahedralMesh &           mesh,
                   const std::vector<std::int32_t> & heldNodes,
                   const std::vector<double> &       heldValues,
                   std::vector<double>               forces,
                   const std::vector<LoadedWall> &   walls,
                   const WallMotionBasis &           basis,
                   std::size_t                       modes,
                   double                            priorWeight);
  ~TrainedWallLoads() override;

  std::size_t
  GetNumberOfParameters() const override;
  const std::vector<std::int32_t> &
  GetConstrainedNodes() const override;
  const std::vector<std::int32_t> &
  GetHeldNodes() const override;
  BoundaryLoad
  Apply(const std::vector<double> & p) const override;
  bool
  IsAffine() const override
  {
    return true;
  }
  BoundaryLoad
  Direction(std::size_t j) const override;
  std::vector<double>
  PullBackGradient(const std::vector<double> & p,
                   const std::vector<double> & prescribedSensitivity,
                   const std::vector<double> & forceSensitivity) const override;
  bool
  ReadsForceSensitivity() const override
  {
    return false;
  }
  bool
  IsReducedBasis() const override
  {
    return true;
  }
  double
  EvaluatePrior(const std::vector<double> & p) const override;
  /** The p of least \f$ |d(p) - u|^2 + w \sum_k p_k^2/\lambda_k \f$ at the control nodes. */
  std::vector<double>
  FitDisplacement(const std::vector<double> & u) const override;
  std::vector<double>
  BoundaryForces(const std::vector<double> & internal) const override;

  /** The control nodes (walls' nodes not held), sorted. */
  const std::vector<std::int32_t> &
  GetControlNodes() const;
  /** How far each control node lay from the basis's atlas surface [mm] (the transfer's error in position). */
  const std::vector<double> &
  GetTransferDistances() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_Impl;
};

} // namespace bmr

#endif

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
#include "bmrOrganSurfaceForces.h"

#include "bmrError.h"
#include "bmrWallBasis.h"

#include <cmath>

namespace bmr {

struct OrganSurfaceForces::Impl
{
  std::vector<std::int32_t>  held;
  std::vector<std::int32_t>  surface;
  std::vector<double>        prescribed; // 3N: the held nodes' values
  std::unique_ptr<WallBasis> basis;
  double                     kappa{ 1.0 };
  double                     alpha{ 0.0 };

  /** 3N nodal forces [mN] of the parameters q. */
  std::vector<double>
  Forces(const std::vector<double> & q) const
  {
    const std::vector<double> onSurface = basis->Expand(q);
    std::vector<double>       f(prescribed.size(), 0.0);
    for (std::size_t k = 0; k < surface.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        f[3 * static_cast<std::size_t>(surface[k]) + c] = kappa * onSurface[3 * k + c];
      }
    }
    return f;
  }
};

OrganSurfaceForces::OrganSurfaceForces(const TetrahedralMesh &           mesh,
                                       const std::vector<std::int32_t> & heldNodes,
                                       const std::vector<double> &       heldValues,
                                       const std::vector<std::int32_t> & surfaceNodes,
                                       double                            controlSpacing)
  : m_Impl(new Impl)
{
  Impl &            d = *m_Impl;
  const std::size_t N = mesh.GetNumberOfPoints();
  if (heldValues.size() != 3 * heldNodes.size())
  {
    Fail("OrganSurfaceForces", "expected 3 held values per held node");
  }
  std::vector<char> isHeld(N, 0);
  d.prescribed.assign(3 * N, 0.0);
  for (std::size_t k = 0; k < heldNodes.size(); ++k)
  {
    const auto n = static_cast<std::size_t>(heldNodes[k]);
    if (n >= N)
    {
      Fail("OrganSurfaceForces", "held node " + std::to_string(n) + " is not a mesh node");
    }
    isHeld[n] = 1;
    for (int c = 0; c < 3; ++c)
    {
      d.prescribed[3 * n + c] = heldValues[3 * k + c];
    }
  }
  for (std::size_t n = 0; n < N; ++n)
  {
    if (isHeld[n])
    {
      d.held.push_back(static_cast<std::int32_t>(n));
    }
  }
  std::vector<char> onSurface(N, 0);
  for (std::int32_t n : surfaceNodes)
  {
    if (n >= 0 && static_cast<std::size_t>(n) < N && !isHeld[n])
    {
      onSurface[n] = 1;
    }
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> wall;
  for (std::size_t n = 0; n < N; ++n)
  {
    if (onSurface[n])
    {
      wall.emplace_back(static_cast<std::int32_t>(d.surface.size()), static_cast<std::int32_t>(n));
      d.surface.push_back(static_cast<std::int32_t>(n));
    }
  }
  if (d.surface.empty())
  {
    Fail("OrganSurfaceForces", "the organ surface has no free node in the mesh");
  }
  d.basis =
    std::make_unique<WallBasis>(mesh.points, std::vector<decltype(wall)>{ wall }, d.surface.size(), controlSpacing);
}

OrganSurfaceForces::~OrganSurfaceForces() = default;

void
OrganSurfaceForces::SetForceScale(double kappa)
{
  if (!std::isfinite(kappa) || kappa <= 0.0)
  {
    Fail("OrganSurfaceForces", "the force scale must be finite and > 0");
  }
  m_Impl->kappa = kappa;
}

void
OrganSurfaceForces::SetRegularization(double alpha)
{
  if (!std::isfinite(alpha) || alpha < 0.0)
  {
    Fail("OrganSurfaceForces", "the regularization must be finite and >= 0");
  }
  m_Impl->alpha = alpha;
}

const std::vector<std::int32_t> &
OrganSurfaceForces::GetSurfaceNodes() const
{
  return m_Impl->surface;
}

std::size_t
OrganSurfaceForces::GetNumberOfParameters() const
{
  return 3 * m_Impl->basis->GetNumberOfControlPoints();
}

const std::vector<std::int32_t> &
OrganSurfaceForces::GetConstrainedNodes() const
{
  return m_Impl->held;
}

const std::vector<std::int32_t> &
OrganSurfaceForces::GetHeldNodes() const
{
  return m_Impl->held;
}

BoundaryLoad
OrganSurfaceForces::Apply(const std::vector<double> & p) const
{
  if (p.size() != GetNumberOfParameters())
  {
    Fail("OrganSurfaceForces",
         "expected " + std::to_string(GetNumberOfParameters()) + " parameters, got " + std::to_string(p.size()));
  }
  return { m_Impl->Forces(p), m_Impl->prescribed };
}

BoundaryLoad
OrganSurfaceForces::Direction(std::size_t j) const
{
  std::vector<double> unit(GetNumberOfParameters(), 0.0);
  unit.at(j) = 1.0;
  return { m_Impl->Forces(unit), std::vector<double>(m_Impl->prescribed.size(), 0.0) };
}

std::vector<double>
OrganSurfaceForces::PullBackGradient(const std::vector<double> & p,
                                     const std::vector<double> &,
                                     const std::vector<double> & forceSensitivity) const
{
  const Impl &        d = *m_Impl;
  std::vector<double> atSurface(3 * d.surface.size(), 0.0);
  for (std::size_t k = 0; k < d.surface.size(); ++k)
  {
    for (int c = 0; c < 3; ++c)
    {
      atSurface[3 * k + c] = d.kappa * forceSensitivity[3 * static_cast<std::size_t>(d.surface[k]) + c];
    }
  }
  std::vector<double> gradient = d.basis->ExpandTranspose(atSurface);
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    gradient[i] += d.alpha * p[i];
  }
  return gradient;
}

double
OrganSurfaceForces::EvaluatePrior(const std::vector<double> & p) const
{
  return RidgePrior(m_Impl->alpha, p);
}

std::vector<double>
OrganSurfaceForces::FitDisplacement(const std::vector<double> &) const
{
  return std::vector<double>(GetNumberOfParameters(), 0.0);
}

std::vector<double>
OrganSurfaceForces::BoundaryForces(const std::vector<double> & internal) const
{
  std::vector<double> F(internal.size(), 0.0);
  for (std::int32_t n : m_Impl->held)
  {
    for (int c = 0; c < 3; ++c)
    {
      F[3 * static_cast<std::size_t>(n) + c] = internal[3 * static_cast<std::size_t>(n) + c];
    }
  }
  return F;
}

} // namespace bmr

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
#include "bmrLoadParameterization.h"

#include "bmrError.h"
#include "bmrWallBasis.h"
#include "bmrWallMotionBasis.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <ostream>
#include <set>

namespace bmr {
void
WallLoadSettings::Validate() const
{
  if (!(controlSpacing >= 0.0 && std::isfinite(controlSpacing)))
  {
    FailInput("WallLoadSettings",
              "controlSpacing must be finite and not negative [mm], got " + std::to_string(controlSpacing));
  }
  if (!(regularization >= 0.0 && std::isfinite(regularization)))
  {
    FailInput("WallLoadSettings",
              "regularization must be finite and not negative, got " + std::to_string(regularization));
  }
  if (trainedBasis == nullptr)
  {
    return;
  }
  if (basisModes > trainedBasis->GetNumberOfModes())
  {
    FailInput("WallLoadSettings",
              "basisModes " + std::to_string(basisModes) + " exceeds the trained basis's " +
                std::to_string(trainedBasis->GetNumberOfModes()) + " modes");
  }
  if (!(basisPriorWeight > 0.0 && std::isfinite(basisPriorWeight)))
  {
    FailInput("WallLoadSettings", "basisPriorWeight must be positive and finite [mm^2]");
  }
  if (controlSpacing > 0.0 || motion == WallMotionEnum::NormalTraction || motion == WallMotionEnum::UniformPressure)
  {
    FailInput("WallLoadSettings",
              "a trained wall basis prescribes the walls' motion itself: no controlSpacing and no tractions with it");
  }
}

namespace {
/** Width [mm] of the Gaussian that averages wall face normals: several voxels (the staircase of a
 * voxelized wall), below the walls' radii of curvature (13 mm for the rectum). */
constexpr double NormalSmoothing = 4.0;

using WallList = std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>>;

/** The area-weighted normal (x1 - x0) x (x2 - x0) of boundary face \a f: twice the face's area long. */
std::array<double, 3>
FaceAreaNormal(const TetrahedralMesh & mesh, std::size_t f)
{
  const std::int32_t * v = &mesh.boundaryFaces[3 * f];
  const double *       x0 = &mesh.points[3 * static_cast<std::size_t>(v[0])];
  const double *       x1 = &mesh.points[3 * static_cast<std::size_t>(v[1])];
  const double *       x2 = &mesh.points[3 * static_cast<std::size_t>(v[2])];
  const double         a[3] = { x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2] };
  const double         b[3] = { x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2] };
  return { { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] } };
}

/** Area-weighted normals of the boundary faces labeled \a faceLabels, summed at each control node. */
std::vector<double>
FaceNormalSums(const TetrahedralMesh &           mesh,
               const std::set<std::int32_t> &    faceLabels,
               const std::vector<std::int32_t> & controlIndex,
               std::size_t                       numberOfControlNodes)
{
  std::vector<double> normals(3 * numberOfControlNodes, 0.0);
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    if (faceLabels.count(mesh.boundaryFaceLabels[f]) == 0)
    {
      continue;
    }
    const std::int32_t *        v = &mesh.boundaryFaces[3 * f];
    const std::array<double, 3> areaNormal = FaceAreaNormal(mesh, f);
    for (int i = 0; i < 3; ++i)
    {
      if (controlIndex[v[i]] >= 0)
      {
        for (int c = 0; c < 3; ++c)
        {
          normals[3 * static_cast<std::size_t>(controlIndex[v[i]]) + c] += areaNormal[c];
        }
      }
    }
  }
  return normals;
}

/** Each control node's share of the area of the boundary faces labeled \a faceLabels (a third of each adjacent
 * face's) [mm^2], and the area of the faces of each label [mm^2]. */
std::vector<double>
NodalFaceAreas(const TetrahedralMesh &           mesh,
               const std::set<std::int32_t> &    faceLabels,
               const std::vector<std::int32_t> & controlIndex,
               std::size_t                       numberOfControlNodes,
               std::map<std::int32_t, double> &  areaOfLabel)
{
  std::vector<double> areas(numberOfControlNodes, 0.0);
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    if (faceLabels.count(mesh.boundaryFaceLabels[f]) == 0)
    {
      continue;
    }
    const std::int32_t *        v = &mesh.boundaryFaces[3 * f];
    const std::array<double, 3> n = FaceAreaNormal(mesh, f);
    const double                area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    areaOfLabel[mesh.boundaryFaceLabels[f]] += area;
    for (int i = 0; i < 3; ++i)
    {
      if (controlIndex[v[i]] >= 0)
      {
        areas[static_cast<std::size_t>(controlIndex[v[i]])] += area / 3.0;
      }
    }
  }
  return areas;
}

/** The faces of a mesh of a voxelized wall tilt with the voxel staircase: Gaussian average of the face
 * normals over NormalSmoothing mm of the same wall, so that "along the normal" means the organ's normal;
 * then unit length (a node on no wall face gets the zero vector). */
std::vector<double>
SmoothedUnitNormals(const TetrahedralMesh & mesh, const WallList & walls, const std::vector<double> & sums)
{
  const double        sigma = NormalSmoothing;
  std::vector<double> smoothed(sums.size(), 0.0);
  for (const auto & wall : walls)
  {
    for (const auto & a : wall)
    {
      const double * xa = &mesh.points[3 * static_cast<std::size_t>(a.second)];
      for (const auto & b : wall)
      {
        const double * xb = &mesh.points[3 * static_cast<std::size_t>(b.second)];
        const double   r2 =
          (xa[0] - xb[0]) * (xa[0] - xb[0]) + (xa[1] - xb[1]) * (xa[1] - xb[1]) + (xa[2] - xb[2]) * (xa[2] - xb[2]);
        if (r2 < 9.0 * sigma * sigma)
        {
          const double w = std::exp(-0.5 * r2 / (sigma * sigma));
          for (int c = 0; c < 3; ++c)
          {
            smoothed[3 * static_cast<std::size_t>(a.first) + c] += w * sums[3 * static_cast<std::size_t>(b.first) + c];
          }
        }
      }
    }
  }
  for (std::size_t k = 0; 3 * k < smoothed.size(); ++k)
  {
    double *     n = &smoothed[3 * k];
    const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int c = 0; c < 3; ++c)
    {
      n[c] = norm > 0.0 ? n[c] / norm : 0.0;
    }
  }
  return smoothed;
}

/** The force per unit parameter and unit shear modulus at each control node k (3 values): 4 v_k / a_w [mm], v_k the
 * node's area vector [mm^2] and a_w = sqrt(A_w / 4 pi) the equivalent radius of the first wall it lies on (A_w the
 * area of that wall's faces, \a areaOfLabel). */
std::vector<double>
LameScaledForces(const std::vector<LoadedWall> &        walls,
                 const std::map<std::int32_t, double> & areaOfLabel,
                 const WallList &                       wallNodes,
                 const std::vector<double> &            areaVectors)
{
  std::vector<double> forces(areaVectors.size(), 0.0);
  std::vector<char>   done(areaVectors.size() / 3, 0);
  for (std::size_t w = 0; w < walls.size(); ++w)
  {
    const auto   area = areaOfLabel.find(walls[w].faceLabel);
    const double radius = area == areaOfLabel.end() ? 0.0 : std::sqrt(area->second / (4.0 * 3.14159265358979323846));
    for (const auto & node : wallNodes[w])
    {
      const auto k = static_cast<std::size_t>(node.first);
      if (!done[k] && radius > 0.0)
      {
        done[k] = 1;
        for (int c = 0; c < 3; ++c)
        {
          forces[3 * k + c] = 4.0 * areaVectors[3 * k + c] / radius;
        }
      }
    }
  }
  return forces;
}

std::vector<double>
FirstComponents(const std::vector<double> & q)
{
  std::vector<double> p(q.size() / 3);
  for (std::size_t j = 0; j < p.size(); ++j)
  {
    p[j] = q[3 * j];
  }
  return p;
}
} // namespace

std::ostream &
operator<<(std::ostream & os, WallMotionEnum value)
{
  switch (value)
  {
    case WallMotionEnum::AlongNormals:
      return os << "bmr::WallMotionEnum::AlongNormals";
    case WallMotionEnum::Free:
      return os << "bmr::WallMotionEnum::Free";
    case WallMotionEnum::NormalTraction:
      return os << "bmr::WallMotionEnum::NormalTraction";
    case WallMotionEnum::UniformPressure:
      return os << "bmr::WallMotionEnum::UniformPressure";
  }
  return os << "INVALID VALUE FOR bmr::WallMotionEnum";
}

struct WallLoads::Impl
{
  const TetrahedralMesh &    mesh;
  std::vector<std::int32_t>  heldNodes;
  std::vector<std::int32_t>  controlNodes;
  std::vector<std::int32_t>  constrained;
  std::vector<double>        basePrescribed; // 3N: the held nodes' values
  std::vector<double>        forces;         // 3N or empty
  WallList                   walls;          // per wall: (control index, mesh node)
  std::vector<double>        normals;        // 3 per control node
  std::vector<double>        tractionForces; // 3 per control node: 4 A_k n_k / a_w [mm], the force per unit s and mu
  std::vector<double>        pressureForces; // the same with the faces' own area vectors: 4 sum_f a_f n_f / 3 a_w
  std::vector<std::int32_t>  heldSorted;
  std::unique_ptr<WallBasis> basis;
  double                     controlSpacing{ 0.0 }; // mm, as set (UniformPressure does not use it)
  double                     regularization{ 0.0 };
  double                     shearModulus{ 1.0 }; // kPa
  WallMotionEnum             motion{ WallMotionEnum::AlongNormals };

  explicit Impl(const TetrahedralMesh & m)
    : mesh(m)
  {}
  bool
  Scalar() const
  {
    return motion != WallMotionEnum::Free;
  }
  bool
  Traction() const
  {
    return motion == WallMotionEnum::NormalTraction || motion == WallMotionEnum::UniformPressure;
  }
  /** The prior's weight: none for a uniform pressure, which has no near-null direction to pick from and whose
   * orthonormal parameter (sqrt(N) s for a wall of N nodes) the ridge would pull toward zero. */
  double
  PriorWeight() const
  {
    return motion == WallMotionEnum::UniformPressure ? 0.0 : regularization;
  }
  /** The force per unit parameter and unit shear modulus at each control node (3 values) of the current motion. */
  const std::vector<double> &
  ForcesPerUnit() const
  {
    return motion == WallMotionEnum::UniformPressure ? pressureForces : tractionForces;
  }
  /** The basis of the current motion: one control point per wall for a uniform pressure (WallBasis' infinite
   * spacing), the set spacing otherwise. */
  void
  RebuildBasis()
  {
    const double spacing =
      motion == WallMotionEnum::UniformPressure ? std::numeric_limits<double>::infinity() : controlSpacing;
    basis.reset(new WallBasis(mesh.points, walls, controlNodes.size(), spacing));
  }
  /** Per control node, 3 values: d = W p, or for a scalar per control point (W s)_k times \a directions_k (the
   * scalar s blended by the same weights: component 0 of the 3-vector basis). */
  std::vector<double>
  Expand(const std::vector<double> & p, const std::vector<double> & directions) const
  {
    if (!Scalar())
    {
      return basis->Expand(p);
    }
    std::vector<double> q(3 * p.size(), 0.0);
    for (std::size_t j = 0; j < p.size(); ++j)
    {
      q[3 * j] = p[j];
    }
    std::vector<double> d = basis->Expand(q);
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      const double amplitude = d[3 * k];
      for (int c = 0; c < 3; ++c)
      {
        d[3 * k + c] = amplitude * directions[3 * k + c];
      }
    }
    return d;
  }
  /** Wall displacement d (3 per control node): d = W p, or along the normals d_k = n_k (W s)_k. */
  std::vector<double>
  Expand(const std::vector<double> & p) const
  {
    return Expand(p, normals);
  }
  /** The nodal forces [mN] (3N) of NormalTraction and UniformPressure: the base forces plus mu (W s)_k times
   * ForcesPerUnit() at control node k. */
  std::vector<double>
  TractionForces(std::vector<double> base, const std::vector<double> & s) const
  {
    base.resize(basePrescribed.size(), 0.0);
    const std::vector<double> f = Expand(s, ForcesPerUnit());
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        base[3 * static_cast<std::size_t>(controlNodes[k]) + c] += shearModulus * f[3 * k + c];
      }
    }
    return base;
  }
  /** Per-control-node vectors projected on \a directions (3 per control node) into component 0. */
  std::vector<double>
  Components(const std::vector<double> & v, const std::vector<double> & directions) const
  {
    std::vector<double> n(v.size(), 0.0);
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        n[3 * k] += directions[3 * k + c] * v[3 * k + c];
      }
    }
    return n;
  }
  std::vector<double>
  NormalComponents(const std::vector<double> & v) const
  {
    return Components(v, normals);
  }
  /** The 3 values per control node of a nodal vector (3N). */
  std::vector<double>
  AtControlNodes(const std::vector<double> & v) const
  {
    std::vector<double> d(3 * controlNodes.size(), 0.0);
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        d[3 * k + c] = v[3 * static_cast<std::size_t>(controlNodes[k]) + c];
      }
    }
    return d;
  }
  /** \a base with the wall displacement \a d written at the control nodes. */
  std::vector<double>
  WithWalls(std::vector<double> base, const std::vector<double> & d) const
  {
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        base[3 * static_cast<std::size_t>(controlNodes[k]) + c] = d[3 * k + c];
      }
    }
    return base;
  }
  std::size_t
  ParametersPerControlPoint() const
  {
    return Scalar() ? 1 : 3;
  }
  void
  CheckSize(const std::vector<double> & p, const char * where) const
  {
    const std::size_t expected = ParametersPerControlPoint() * basis->GetNumberOfControlPoints();
    if (p.size() != expected)
    {
      Fail(where, "expected " + std::to_string(expected) + " load parameters, got " + std::to_string(p.size()));
    }
  }
};

WallLoads::WallLoads(const TetrahedralMesh &           mesh,
                     const std::vector<std::int32_t> & heldNodes,
                     const std::vector<double> &       heldValues,
                     std::vector<double>               forces,
                     const std::vector<LoadedWall> &   walls)
  : m_Impl(new Impl(mesh))
{
  Impl &            d = *m_Impl;
  const std::size_t N = mesh.GetNumberOfPoints();
  if (heldValues.size() != 3 * heldNodes.size() || !(forces.empty() || forces.size() == 3 * N))
  {
    Fail("WallLoads", "expected 3 held values per held node and 3 forces per mesh node");
  }
  d.heldNodes = heldNodes;
  d.forces = std::move(forces);
  std::vector<char> held(N, 0);
  d.basePrescribed.assign(3 * N, 0.0);
  for (std::size_t k = 0; k < heldNodes.size(); ++k)
  {
    held[heldNodes[k]] = 1;
    for (int c = 0; c < 3; ++c)
    {
      d.basePrescribed[3 * static_cast<std::size_t>(heldNodes[k]) + c] = heldValues[3 * k + c];
    }
  }
  std::set<std::int32_t>              control, faceLabels;
  std::vector<std::set<std::int32_t>> wallOf(N); // walls (by index) each node is on
  for (std::size_t w = 0; w < walls.size(); ++w)
  {
    std::size_t added = 0;
    for (std::int32_t n : walls[w].nodes)
    {
      if (!held[n])
      {
        control.insert(n);
        wallOf[n].insert(static_cast<std::int32_t>(w));
        ++added;
      }
    }
    if (added == 0)
    {
      Fail("WallLoads", "force surface \"" + walls[w].name + "\" has no free wall node in the mesh");
    }
    faceLabels.insert(walls[w].faceLabel);
  }
  d.controlNodes.assign(control.begin(), control.end());
  d.walls.assign(walls.size(), {});
  std::vector<std::int32_t> controlIndex(N, -1);
  for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
  {
    controlIndex[d.controlNodes[k]] = static_cast<std::int32_t>(k);
    for (std::int32_t w : wallOf[d.controlNodes[k]])
    {
      d.walls[w].emplace_back(static_cast<std::int32_t>(k), d.controlNodes[k]);
    }
  }
  d.RebuildBasis();
  const std::vector<double> normalSums = FaceNormalSums(mesh, faceLabels, controlIndex, d.controlNodes.size());
  d.normals = SmoothedUnitNormals(mesh, d.walls, normalSums);
  // A traction that varies along the wall acts along the smoothed normal on the node's share of the area; a uniform
  // pressure p loads node k with p sum_f a_f n_f / 3 over its faces, exactly the consistent P1 load, whose
  // staircase tilts cancel over the wall as the pressure's do.
  std::map<std::int32_t, double> areaOfLabel;
  const std::vector<double>      nodeArea =
    NodalFaceAreas(mesh, faceLabels, controlIndex, d.controlNodes.size(), areaOfLabel);
  std::vector<double> smoothedAreaVectors(d.normals.size()), faceAreaVectors(d.normals.size());
  for (std::size_t i = 0; i < d.normals.size(); ++i)
  {
    smoothedAreaVectors[i] = nodeArea[i / 3] * d.normals[i];
    faceAreaVectors[i] = normalSums[i] / 6.0; // the sums are of cross products, twice each face's area
  }
  d.tractionForces = LameScaledForces(walls, areaOfLabel, d.walls, smoothedAreaVectors);
  d.pressureForces = LameScaledForces(walls, areaOfLabel, d.walls, faceAreaVectors);
  d.heldSorted = heldNodes;
  std::sort(d.heldSorted.begin(), d.heldSorted.end());
  d.constrained = heldNodes;
  d.constrained.insert(d.constrained.end(), d.controlNodes.begin(), d.controlNodes.end());
  std::sort(d.constrained.begin(), d.constrained.end());
}

WallLoads::~WallLoads() = default;

void
WallLoads::SetControlSpacing(double spacing)
{
  if (!std::isfinite(spacing))
  {
    Fail("WallLoads::SetControlSpacing", "the control point spacing must be finite");
  }
  m_Impl->controlSpacing = spacing;
  m_Impl->RebuildBasis();
}

bool
WallLoads::IsReducedBasis() const
{
  WallLoadSettings settings; // the one rule, WallLoadSettings::ReducedBasis()
  settings.controlSpacing = m_Impl->controlSpacing;
  settings.motion = m_Impl->motion;
  return settings.ReducedBasis();
}

void
WallLoads::SetRegularization(double alpha)
{
  if (!(std::isfinite(alpha) && alpha >= 0.0))
  {
    Fail("WallLoads::SetRegularization", "the regularization weight must be finite and >= 0");
  }
  m_Impl->regularization = alpha;
}

void
WallLoads::SetMotion(WallMotionEnum motion)
{
  const bool traction = motion == WallMotionEnum::NormalTraction || motion == WallMotionEnum::UniformPressure;
  if (traction && m_Impl->heldNodes.empty())
  {
    Fail("WallLoads::SetMotion",
         "normal tractions on the walls leave no node held: nothing keeps the mesh in place "
         "(the scene needs a fixed label or a fixed region-of-interest boundary)");
  }
  const bool basisChanges =
    (m_Impl->motion == WallMotionEnum::UniformPressure) != (motion == WallMotionEnum::UniformPressure);
  m_Impl->motion = motion;
  if (basisChanges)
  {
    m_Impl->RebuildBasis();
  }
}

void
WallLoads::SetTractionShearModulus(double mu)
{
  if (!(std::isfinite(mu) && mu > 0.0))
  {
    Fail("WallLoads::SetTractionShearModulus", "the shear modulus must be finite and > 0 kPa");
  }
  m_Impl->shearModulus = mu;
}

WallMotionEnum
WallLoads::GetMotion() const
{
  return m_Impl->motion;
}

const std::vector<std::int32_t> &
WallLoads::GetControlNodes() const
{
  return m_Impl->controlNodes;
}

std::size_t
WallLoads::GetNumberOfParameters() const
{
  return m_Impl->ParametersPerControlPoint() * m_Impl->basis->GetNumberOfControlPoints();
}

const std::vector<std::int32_t> &
WallLoads::GetConstrainedNodes() const
{
  return m_Impl->Traction() ? m_Impl->heldSorted : m_Impl->constrained;
}

const std::vector<std::int32_t> &
WallLoads::GetHeldNodes() const
{
  return m_Impl->heldNodes;
}

BoundaryLoad
WallLoads::Apply(const std::vector<double> & p) const
{
  m_Impl->CheckSize(p, "WallLoads::Apply");
  if (m_Impl->Traction())
  {
    return { m_Impl->TractionForces(m_Impl->forces, p), m_Impl->basePrescribed };
  }
  return { m_Impl->forces, m_Impl->WithWalls(m_Impl->basePrescribed, m_Impl->Expand(p)) };
}

BoundaryLoad
WallLoads::Direction(std::size_t j) const
{
  std::vector<double> unit(GetNumberOfParameters(), 0.0);
  unit.at(j) = 1.0;
  const std::vector<double> zero(m_Impl->basePrescribed.size(), 0.0);
  if (m_Impl->Traction())
  {
    return { m_Impl->TractionForces(zero, unit), zero };
  }
  return { {}, m_Impl->WithWalls(zero, m_Impl->Expand(unit)) };
}

bool
WallLoads::ReadsForceSensitivity() const
{
  return m_Impl->Traction();
}

std::vector<double>
WallLoads::PullBackGradient(const std::vector<double> & p,
                            const std::vector<double> & prescribedSensitivity,
                            const std::vector<double> & forceSensitivity) const
{
  const Impl & d = *m_Impl;
  // Traction: dPhi/df at the walls (the adjoint), through f_k = mu 4 A_k n_k / a_w (W s)_k.
  const std::vector<double> atWalls = d.AtControlNodes(d.Traction() ? forceSensitivity : prescribedSensitivity);
  std::vector<double>       gradient;
  if (d.Traction())
  {
    std::vector<double> h = d.Components(atWalls, d.ForcesPerUnit());
    for (double & x : h)
    {
      x *= d.shearModulus;
    }
    gradient = FirstComponents(d.basis->ExpandTranspose(h));
  }
  else
  {
    gradient = d.Scalar() ? FirstComponents(d.basis->ExpandTranspose(d.NormalComponents(atWalls)))
                          : d.basis->ExpandTranspose(atWalls);
  }
  for (std::size_t i = 0; i < p.size(); ++i)
  {
    gradient[i] += d.PriorWeight() * p[i];
  }
  return gradient;
}

double
WallLoads::EvaluatePrior(const std::vector<double> & p) const
{
  return RidgePrior(m_Impl->PriorWeight(), p);
}

std::vector<double>
WallLoads::FitDisplacement(const std::vector<double> & u) const
{
  const Impl &              d = *m_Impl;
  const std::vector<double> atWalls = d.AtControlNodes(u);
  // Traction: s reads as millimetres of normal wall motion (the Lamé scale), so the normal motion is the start.
  return d.Scalar() ? FirstComponents(d.basis->Fit(d.NormalComponents(atWalls))) : d.basis->Fit(atWalls);
}

std::vector<double>
WallLoads::BoundaryForces(const std::vector<double> & internal) const
{
  return ReactionForcesAt(m_Impl->controlNodes, internal, m_Impl->forces);
}

std::vector<double>
ReactionForcesAt(const std::vector<std::int32_t> & nodes,
                 const std::vector<double> &       internal,
                 const std::vector<double> &       forces)
{
  std::vector<double> F(internal.size(), 0.0);
  for (std::int32_t n : nodes)
  {
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t dof = 3 * static_cast<std::size_t>(n) + c;
      F[dof] = internal[dof] - (forces.empty() ? 0.0 : forces[dof]);
    }
  }
  return F;
}

} // namespace bmr

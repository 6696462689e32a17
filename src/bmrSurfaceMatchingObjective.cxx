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
#include "bmrSurfaceMatchingObjective.h"

#include "bmrError.h"
#include "bmrSimulation.h"
#include "bmrWallBasis.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <utility>

namespace bmr {
namespace {
/** Width [mm] of the Gaussian that averages wall face normals for the sliding penalty: several voxels
 * (the staircase of a voxelised wall), below the walls' radii of curvature (13 mm for the rectum). */
constexpr double NormalSmoothing = 4.0;

/** Nodes of the wall of an excluded label, or of the surface of a simulated one. */
std::vector<std::int32_t>
SurfaceNodes(const Scene & scene, const TetrahedralMesh & mesh, const SceneLabel & label)
{
  const bool simulated = label.role == LabelRole::Material || label.role == LabelRole::UnknownMaterial;
  if (simulated)
  {
    return NodesOnLabelSurface(mesh, label.value);
  }
  // Outside labels are mapped to 0 before meshing: their wall is the outer boundary.
  const bool outside = label.role == LabelRole::Outside;
  (void)scene;
  return NodesOnBoundary(mesh, outside ? 0 : label.value);
}
} // namespace

std::vector<ObjectiveSurface>
SceneObjectiveSurfaces(const Scene &                                                                scene,
                       const TetrahedralMesh &                                                      mesh,
                       const std::map<std::int32_t, std::shared_ptr<const SignedDistanceSampler>> & maps)
{
  std::vector<ObjectiveSurface> surfaces;
  for (const ObjectiveTerm & term : scene.objective)
  {
    const SceneLabel * label = scene.FindLabel(term.label);
    if (label == nullptr)
    {
      Fail("SceneObjectiveSurfaces", "objective label \"" + term.label + "\" is not defined in the scene");
    }
    const auto map = maps.find(label->value);
    if (map == maps.end() || !map->second)
    {
      Fail("SceneObjectiveSurfaces", "no distance map was given for objective label \"" + term.label + "\"");
    }
    ObjectiveSurface s;
    s.name = term.label;
    s.label = label->value;
    s.weight = term.weight;
    s.nodes = SurfaceNodes(scene, mesh, *label);
    s.distance = map->second;
    if (s.nodes.empty())
    {
      Fail("SceneObjectiveSurfaces", "objective label \"" + term.label + "\" has no surface node in the mesh");
    }
    surfaces.push_back(std::move(s));
  }
  return surfaces;
}

struct SurfaceMatchingObjective::Impl
{
  const TetrahedralMesh &             mesh;
  std::vector<ObjectiveSurface>       surfaces;
  BoundaryConditions                  bc;
  std::vector<std::int32_t>           controlNodes;
  std::vector<std::int32_t>           unknownLabels;
  std::vector<double>                 basePrescribed; // 3N: fixed walls' values
  std::unique_ptr<LinearElasticModel> model;
  // Walls as (control index, mesh node) lists, and the basis of their displacement.
  std::vector<std::vector<std::pair<std::int32_t, std::int32_t>>> walls;
  std::unique_ptr<WallBasis>                                      basis;
  double                                                          regularization{ 0.0 };
  bool                                                            normalMotion{ true };
  std::size_t                                                     inverted{ 0 }; // by the last Evaluate()

  std::vector<double> wallNormals; // 3 per control node: unit normal of the wall there

  std::size_t
  ParametersPerControlPoint() const
  {
    return normalMotion ? 1 : 3;
  }
  /** Wall displacement d (3 per control node) from the parameters: d = W p, or with normal motion
   * d_k = n_k (W s)_k, the scalar s blended by the same weights (component 0 of the 3-vector basis). */
  std::vector<double>
  Expand(const std::vector<double> & p) const
  {
    if (!normalMotion)
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
        d[3 * k + c] = amplitude * wallNormals[3 * k + c];
      }
    }
    return d;
  }
  /** Projects per-node vectors on the normals (normal motion) into component 0; identity otherwise. */
  std::vector<double>
  NormalComponents(const std::vector<double> & v) const
  {
    std::vector<double> n(v.size(), 0.0);
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        n[3 * k] += wallNormals[3 * k + c] * v[3 * k + c];
      }
    }
    return n;
  }
  static std::vector<double>
  FirstComponents(const std::vector<double> & q)
  {
    std::vector<double> p(q.size() / 3);
    for (std::size_t j = 0; j < p.size(); ++j)
    {
      p[j] = q[3 * j];
    }
    return p;
  }
  /** The gradient with respect to the parameters of a function of d with gradient g. */
  std::vector<double>
  ExpandTranspose(const std::vector<double> & g) const
  {
    return normalMotion ? FirstComponents(basis->ExpandTranspose(NormalComponents(g))) : basis->ExpandTranspose(g);
  }
  /** Least-squares parameters of a wall displacement (its normal part with normal motion). */
  std::vector<double>
  Fit(const std::vector<double> & d) const
  {
    return normalMotion ? FirstComponents(basis->Fit(NormalComponents(d))) : basis->Fit(d);
  }

  explicit Impl(const TetrahedralMesh & m)
    : mesh(m)
  {}

  std::vector<double>
  Prescribed(const std::vector<double> & d) const
  {
    if (d.size() != 3 * controlNodes.size())
    {
      std::ostringstream msg;
      msg << "expected " << 3 * controlNodes.size() << " wall displacement values (3 per control node), got "
          << d.size();
      Fail("SurfaceMatchingObjective", msg.str());
    }
    std::vector<double> p = basePrescribed;
    for (std::size_t k = 0; k < controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        p[3 * static_cast<std::size_t>(controlNodes[k]) + c] = d[3 * k + c];
      }
    }
    return p;
  }
};

SurfaceMatchingObjective::SurfaceMatchingObjective(const TetrahedralMesh &       mesh,
                                                   const Scene &                 scene,
                                                   std::vector<ObjectiveSurface> surfaces)
  : m_Impl(new Impl(mesh))
{
  Impl & d = *m_Impl;
  if (surfaces.empty())
  {
    Fail("SurfaceMatchingObjective", "the scene's objective is empty: nothing to match");
  }
  d.surfaces = std::move(surfaces);
  d.bc = SceneBoundaryConditions(scene, mesh);
  const std::size_t N = mesh.GetNumberOfPoints();
  std::vector<char> held(N, 0);
  for (std::int32_t n : d.bc.dirichletNodes)
  {
    held[n] = 1;
  }
  std::set<std::int32_t>              control;
  std::vector<std::set<std::int32_t>> wallOf(N); // force surfaces (by index) each node is on
  std::size_t                         wallIndex = 0;
  for (const std::string & name : scene.forceSurfaces)
  {
    const SceneLabel * label = scene.FindLabel(name);
    if (label == nullptr)
    {
      Fail("SurfaceMatchingObjective", "force surface \"" + name + "\" is not defined in the scene");
    }
    const std::vector<std::int32_t> wall = SurfaceNodes(scene, mesh, *label);
    std::size_t                     added = 0;
    for (std::int32_t n : wall)
    {
      if (!held[n])
      {
        control.insert(n);
        wallOf[n].insert(static_cast<std::int32_t>(wallIndex));
        ++added;
      }
    }
    ++wallIndex;
    if (added == 0)
    {
      Fail("SurfaceMatchingObjective", "force surface \"" + name + "\" has no free wall node in the mesh");
    }
  }
  d.controlNodes.assign(control.begin(), control.end());
  d.walls.assign(wallIndex, {});
  for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
  {
    for (std::int32_t w : wallOf[d.controlNodes[k]])
    {
      d.walls[w].emplace_back(static_cast<std::int32_t>(k), d.controlNodes[k]);
    }
  }
  d.basis.reset(new WallBasis(mesh.points, d.walls, d.controlNodes.size(), 0.0));
  // Wall normals: area-weighted normals of the boundary faces of the force surfaces around each control node.
  {
    std::set<std::int32_t> wallLabels;
    for (const std::string & name : scene.forceSurfaces)
    {
      const SceneLabel * label = scene.FindLabel(name);
      wallLabels.insert(label->role == LabelRole::Outside ? 0 : label->value);
    }
    std::vector<std::int32_t> controlIndex(N, -1);
    for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
    {
      controlIndex[d.controlNodes[k]] = static_cast<std::int32_t>(k);
    }
    d.wallNormals.assign(3 * d.controlNodes.size(), 0.0);
    for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
    {
      if (wallLabels.count(mesh.boundaryFaceLabels[f]) == 0)
      {
        continue;
      }
      const std::int32_t * v = &mesh.boundaryFaces[3 * f];
      const double *       x0 = &mesh.points[3 * static_cast<std::size_t>(v[0])];
      const double *       x1 = &mesh.points[3 * static_cast<std::size_t>(v[1])];
      const double *       x2 = &mesh.points[3 * static_cast<std::size_t>(v[2])];
      const double         a[3] = { x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2] };
      const double         b[3] = { x2[0] - x0[0], x2[1] - x0[1], x2[2] - x0[2] };
      const double areaNormal[3] = { a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0] };
      for (int i = 0; i < 3; ++i)
      {
        if (controlIndex[v[i]] >= 0)
        {
          for (int c = 0; c < 3; ++c)
          {
            d.wallNormals[3 * static_cast<std::size_t>(controlIndex[v[i]]) + c] += areaNormal[c];
          }
        }
      }
    }
    // The faces of a mesh of a voxelised wall tilt with the voxel staircase: Gaussian average of the face
    // normals over NormalSmoothing mm of the same wall, so that "along the normal" means the organ's normal.
    const double        sigma = NormalSmoothing;
    std::vector<double> smoothed(d.wallNormals.size(), 0.0);
    for (const auto & wall : d.walls)
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
              smoothed[3 * static_cast<std::size_t>(a.first) + c] +=
                w * d.wallNormals[3 * static_cast<std::size_t>(b.first) + c];
            }
          }
        }
      }
    }
    d.wallNormals.swap(smoothed);
    for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
    {
      double *     n = &d.wallNormals[3 * k];
      const double norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int c = 0; c < 3; ++c)
      {
        n[c] = norm > 0.0 ? n[c] / norm : 0.0; // a node on no wall face gets no sliding penalty
      }
    }
  }
  for (const auto & l : scene.labels)
  {
    if (l.role == LabelRole::UnknownMaterial)
    {
      d.unknownLabels.push_back(l.value);
    }
  }
  if (d.controlNodes.empty() && d.unknownLabels.empty())
  {
    Fail("SurfaceMatchingObjective",
         "the scene has neither an unknown modulus (role unknown_material) nor a force surface: nothing to estimate");
  }
  d.basePrescribed.assign(3 * N, 0.0);
  for (std::size_t k = 0; k < d.bc.dirichletNodes.size(); ++k)
  {
    for (int c = 0; c < 3; ++c)
    {
      d.basePrescribed[3 * static_cast<std::size_t>(d.bc.dirichletNodes[k]) + c] = d.bc.dirichletValues[3 * k + c];
    }
  }
  std::vector<std::int32_t> constrained = d.bc.dirichletNodes;
  constrained.insert(constrained.end(), d.controlNodes.begin(), d.controlNodes.end());
  std::sort(constrained.begin(), constrained.end());
  d.model.reset(new LinearElasticModel(mesh, SceneMaterials(scene)));
  d.model->SetDirichletConditions(constrained, {});
}

SurfaceMatchingObjective::~SurfaceMatchingObjective() = default;

std::size_t
SurfaceMatchingObjective::GetNumberOfParameters() const
{
  return m_Impl->ParametersPerControlPoint() * m_Impl->basis->GetNumberOfControlPoints();
}

void
SurfaceMatchingObjective::SetWallRegularization(double alpha)
{
  if (!(std::isfinite(alpha) && alpha >= 0.0))
  {
    Fail("SurfaceMatchingObjective::SetWallRegularization", "the regularisation weight must be finite and >= 0");
  }
  m_Impl->regularization = alpha;
}

void
SurfaceMatchingObjective::SetWallMotionAlongNormals(bool normal)
{
  m_Impl->normalMotion = normal;
}

void
SurfaceMatchingObjective::SetWallControlSpacing(double spacing)
{
  if (!std::isfinite(spacing))
  {
    Fail("SurfaceMatchingObjective::SetWallControlSpacing", "the control point spacing must be finite");
  }
  m_Impl->basis.reset(new WallBasis(m_Impl->mesh.points, m_Impl->walls, m_Impl->controlNodes.size(), spacing));
}

const std::vector<std::int32_t> &
SurfaceMatchingObjective::GetUnknownLabels() const
{
  return m_Impl->unknownLabels;
}

void
SurfaceMatchingObjective::SetYoungsModuli(const std::vector<double> & moduli)
{
  if (moduli.size() != m_Impl->unknownLabels.size())
  {
    Fail("SurfaceMatchingObjective::SetYoungsModuli", "expected one modulus per unknown material");
  }
  for (std::size_t m = 0; m < moduli.size(); ++m)
  {
    m_Impl->model->SetYoungsModulus(m_Impl->unknownLabels[m], moduli[m]);
  }
}

double
SurfaceMatchingObjective::Evaluate(const std::vector<double> & parameters,
                                   std::vector<double> *       gradientD,
                                   std::vector<double> *       gradientLogE)
{
  Impl & d = *m_Impl;
  if (parameters.size() != GetNumberOfParameters())
  {
    Fail("SurfaceMatchingObjective::Evaluate",
         "expected " + std::to_string(GetNumberOfParameters()) + " parameters, got " +
           std::to_string(parameters.size()));
  }
  const std::vector<double> dWall = d.Expand(parameters);
  const std::vector<double> u = d.model->Solve(d.bc.forces, d.Prescribed(dWall));
  d.inverted = CountInvertedElements(d.mesh, u);
  const bool          wantGradient = gradientD != nullptr || gradientLogE != nullptr;
  std::vector<double> g(wantGradient ? u.size() : 0, 0.0);
  double              phiSum = 0.0;
  for (const ObjectiveSurface & s : d.surfaces)
  {
    for (std::int32_t n : s.nodes)
    {
      const double x[3] = { d.mesh.points[3 * n] + u[3 * n],
                            d.mesh.points[3 * n + 1] + u[3 * n + 1],
                            d.mesh.points[3 * n + 2] + u[3 * n + 2] };
      double       grad[3];
      const double phi = s.distance->Evaluate(x, grad);
      phiSum += 0.5 * s.weight * phi * phi;
      if (wantGradient)
      {
        for (int c = 0; c < 3; ++c)
        {
          g[3 * n + c] += s.weight * phi * grad[c];
        }
      }
    }
  }
  double pp = 0.0;
  for (double x : parameters)
  {
    pp += x * x;
  }
  phiSum += 0.5 * d.regularization * pp;
  if (!wantGradient)
  {
    return phiSum;
  }
  // Adjoint: K_ff lambda_f = g_f, lambda = 0 on every constrained dof.
  const std::vector<double> lambda = d.model->Solve(g, std::vector<double>(u.size(), 0.0));
  if (gradientD != nullptr)
  {
    const std::vector<double> Klambda = d.model->ComputeInternalForces(lambda);
    gradientD->assign(3 * d.controlNodes.size(), 0.0);
    for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        const std::size_t dof = 3 * static_cast<std::size_t>(d.controlNodes[k]) + c;
        (*gradientD)[3 * k + c] = g[dof] - Klambda[dof];
      }
    }
    *gradientD = d.ExpandTranspose(*gradientD);
    for (std::size_t i = 0; i < parameters.size(); ++i)
    {
      (*gradientD)[i] += d.regularization * parameters[i];
    }
  }
  if (gradientLogE != nullptr)
  {
    gradientLogE->assign(d.unknownLabels.size(), 0.0);
    for (std::size_t m = 0; m < d.unknownLabels.size(); ++m)
    {
      const std::vector<double> Ku = d.model->ComputeMaterialStiffnessProduct(d.unknownLabels[m], u);
      double                    dot = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i)
      {
        dot += lambda[i] * Ku[i];
      }
      (*gradientLogE)[m] = -d.model->GetYoungsModulus(d.unknownLabels[m]) * dot;
    }
  }
  return phiSum;
}

std::vector<double>
SurfaceMatchingObjective::ComputeDisplacement(const std::vector<double> & parameters)
{
  return m_Impl->model->Solve(m_Impl->bc.forces, m_Impl->Prescribed(m_Impl->Expand(parameters)));
}

std::vector<double>
SurfaceMatchingObjective::ComputeBoundaryForces(const std::vector<double> & u) const
{
  const std::vector<double> Ku = m_Impl->model->ComputeInternalForces(u);
  std::vector<double>       F(Ku.size(), 0.0);
  for (std::int32_t n : m_Impl->controlNodes)
  {
    for (int c = 0; c < 3; ++c)
    {
      const std::size_t dof = 3 * static_cast<std::size_t>(n) + c;
      F[dof] = Ku[dof] - m_Impl->bc.forces[dof];
    }
  }
  return F;
}

std::size_t
SurfaceMatchingObjective::GetNumberOfInvertedElements() const
{
  return m_Impl->inverted;
}

std::vector<SurfaceDistanceStatistics>
SurfaceMatchingObjective::ComputeSurfaceDistances(const std::vector<double> & u) const
{
  const TetrahedralMesh &                mesh = m_Impl->mesh;
  std::vector<SurfaceDistanceStatistics> stats;
  for (const ObjectiveSurface & s : m_Impl->surfaces)
  {
    SurfaceDistanceStatistics st;
    st.name = s.name;
    st.nodes = s.nodes.size();
    double sum = 0.0;
    for (std::int32_t n : s.nodes)
    {
      const double x[3] = { mesh.points[3 * n] + u[3 * n],
                            mesh.points[3 * n + 1] + u[3 * n + 1],
                            mesh.points[3 * n + 2] + u[3 * n + 2] };
      const double phi = s.distance->Evaluate(x, nullptr);
      sum += phi * phi;
      st.mean += phi / static_cast<double>(s.nodes.size());
      st.maximum = std::max(st.maximum, std::abs(phi));
    }
    st.rms = std::sqrt(sum / static_cast<double>(s.nodes.size()));
    stats.push_back(st);
  }
  return stats;
}

std::vector<double>
SurfaceMatchingObjective::MatchSurfaces(unsigned int iterations) const
{
  const Impl &      d = *m_Impl;
  const std::size_t N = d.mesh.GetNumberOfPoints();
  // Which surfaces each node is on, and its neighbours along element edges on a common surface.
  std::vector<std::vector<std::size_t>> onSurface(N);
  for (std::size_t s = 0; s < d.surfaces.size(); ++s)
  {
    for (std::int32_t n : d.surfaces[s].nodes)
    {
      onSurface[n].push_back(s);
    }
  }
  const auto shareSurface = [&](std::int32_t a, std::int32_t b) {
    for (std::size_t s : onSurface[a])
    {
      if (std::find(onSurface[b].begin(), onSurface[b].end(), s) != onSurface[b].end())
      {
        return true;
      }
    }
    return false;
  };
  std::vector<std::vector<std::int32_t>> neighbours(N);
  for (std::size_t e = 0; e < d.mesh.GetNumberOfTetrahedra(); ++e)
  {
    const std::int32_t * t = &d.mesh.tetrahedra[4 * e];
    for (int a = 0; a < 4; ++a)
    {
      for (int b = 0; b < 4; ++b)
      {
        if (a != b && !onSurface[t[a]].empty() && shareSurface(t[a], t[b]))
        {
          neighbours[t[a]].push_back(t[b]);
        }
      }
    }
  }
  std::vector<std::int32_t> active;
  for (std::size_t n = 0; n < N; ++n)
  {
    auto & nb = neighbours[n];
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    if (!onSurface[n].empty())
    {
      active.push_back(static_cast<std::int32_t>(n));
    }
  }
  std::vector<char> held(N, 0);
  for (std::int32_t n : d.bc.dirichletNodes)
  {
    held[n] = 1;
  }
  // alpha: fraction of the distance closed per step; beta: spring stiffness towards the neighbours' mean.
  const double        alpha = 0.5, beta = 0.25;
  std::vector<double> v(3 * N, 0.0), next(3 * N, 0.0);
  for (unsigned int it = 0; it < iterations; ++it)
  {
    for (std::int32_t n : active)
    {
      if (held[n])
      {
        continue;
      }
      double pull[3] = { 0.0, 0.0, 0.0 };
      for (std::size_t s : onSurface[n])
      {
        const double x[3] = { d.mesh.points[3 * n] + v[3 * n],
                              d.mesh.points[3 * n + 1] + v[3 * n + 1],
                              d.mesh.points[3 * n + 2] + v[3 * n + 2] };
        double       grad[3];
        const double phi = d.surfaces[s].distance->Evaluate(x, grad);
        for (int c = 0; c < 3; ++c)
        {
          pull[c] -= phi * grad[c] / static_cast<double>(onSurface[n].size());
        }
      }
      double mean[3] = { 0.0, 0.0, 0.0 };
      for (std::int32_t m : neighbours[n])
      {
        for (int c = 0; c < 3; ++c)
        {
          mean[c] += v[3 * m + c] / static_cast<double>(neighbours[n].size());
        }
      }
      for (int c = 0; c < 3; ++c)
      {
        const double vc = v[3 * n + c];
        next[3 * n + c] = vc + alpha * pull[c] + (neighbours[n].empty() ? 0.0 : beta * (mean[c] - vc));
      }
    }
    for (std::int32_t n : active)
    {
      if (!held[n])
      {
        for (int c = 0; c < 3; ++c)
        {
          v[3 * n + c] = next[3 * n + c];
        }
      }
    }
  }
  std::vector<double> dWall(3 * d.controlNodes.size(), 0.0);
  for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
  {
    for (int c = 0; c < 3; ++c)
    {
      dWall[3 * k + c] = v[3 * static_cast<std::size_t>(d.controlNodes[k]) + c];
    }
  }
  return d.Fit(dWall);
}

WallSolution
SurfaceMatchingObjective::SolveWalls(const std::vector<double> & start,
                                     unsigned int                maximumIterations,
                                     double                      tolerance)
{
  Impl &            d = *m_Impl;
  const std::size_t np = GetNumberOfParameters();
  if (start.size() != np)
  {
    Fail("SurfaceMatchingObjective::SolveWalls",
         "the start holds " + std::to_string(start.size()) + " values, expected " + std::to_string(np));
  }
  // Objective entries (surface, node) and the distinct nodes they need.
  std::vector<std::int32_t> nodes;
  for (const ObjectiveSurface & s : d.surfaces)
  {
    nodes.insert(nodes.end(), s.nodes.begin(), s.nodes.end());
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<std::int32_t> row(d.mesh.GetNumberOfPoints(), -1);
  for (std::size_t i = 0; i < nodes.size(); ++i)
  {
    row[nodes[i]] = static_cast<std::int32_t>(i);
  }
  // u is affine in p: u = u0 + A p. Columns of A by one solve each with the cached factorisation.
  const std::vector<double> u0 =
    d.model->Solve(d.bc.forces, d.Prescribed(std::vector<double>(3 * d.controlNodes.size(), 0.0)));
  Eigen::MatrixXd     A(static_cast<Eigen::Index>(3 * nodes.size()), static_cast<Eigen::Index>(np));
  std::vector<double> unit(np, 0.0), wallsOnly(u0.size(), 0.0);
  for (std::size_t j = 0; j < np; ++j)
  {
    unit[j] = 1.0;
    const std::vector<double> dj = d.Expand(unit);
    unit[j] = 0.0;
    for (std::size_t k = 0; k < d.controlNodes.size(); ++k)
    {
      for (int c = 0; c < 3; ++c)
      {
        wallsOnly[3 * static_cast<std::size_t>(d.controlNodes[k]) + c] = dj[3 * k + c];
      }
    }
    const std::vector<double> uj = d.model->Solve({}, wallsOnly);
    for (std::size_t i = 0; i < nodes.size(); ++i)
    {
      for (int c = 0; c < 3; ++c)
      {
        A(static_cast<Eigen::Index>(3 * i + c), static_cast<Eigen::Index>(j)) =
          uj[3 * static_cast<std::size_t>(nodes[i]) + c];
      }
    }
  }
  std::size_t entries = 0;
  for (const ObjectiveSurface & s : d.surfaces)
  {
    entries += s.nodes.size();
  }
  // Residuals r = sqrt(w) phi(x + u) and their Jacobian J = sqrt(w) grad(phi)^T A.
  const auto residuals = [&](const Eigen::VectorXd & p, Eigen::VectorXd & r, Eigen::MatrixXd * J) {
    const Eigen::VectorXd u = A * p;
    r.resize(static_cast<Eigen::Index>(entries));
    if (J)
    {
      J->resize(static_cast<Eigen::Index>(entries), static_cast<Eigen::Index>(np));
    }
    Eigen::Index k = 0;
    for (const ObjectiveSurface & s : d.surfaces)
    {
      const double sw = std::sqrt(s.weight);
      for (std::int32_t n : s.nodes)
      {
        const std::size_t i = static_cast<std::size_t>(row[n]);
        double            x[3];
        for (int c = 0; c < 3; ++c)
        {
          x[c] = d.mesh.points[3 * static_cast<std::size_t>(n) + c] + u0[3 * static_cast<std::size_t>(n) + c] +
                 u[static_cast<Eigen::Index>(3 * i + c)];
        }
        double grad[3];
        r[k] = sw * s.distance->Evaluate(x, grad);
        if (J)
        {
          J->row(k) = sw * (grad[0] * A.row(static_cast<Eigen::Index>(3 * i)) +
                            grad[1] * A.row(static_cast<Eigen::Index>(3 * i + 1)) +
                            grad[2] * A.row(static_cast<Eigen::Index>(3 * i + 2)));
        }
        ++k;
      }
    }
    return 0.5 * r.squaredNorm() + 0.5 * d.regularization * p.squaredNorm();
  };
  // Levenberg-Marquardt: (J^T J + mu diag(J^T J)) delta = -J^T r; mu shrinks after a success, grows after a failure.
  Eigen::VectorXd p = Eigen::Map<const Eigen::VectorXd>(start.data(), static_cast<Eigen::Index>(np));
  Eigen::VectorXd r, rTry;
  Eigen::MatrixXd J;
  double          value = residuals(p, r, &J);
  double          mu = 1e-3;
  WallSolution    result;
  result.stop = "maximum number of iterations";
  unsigned int it = 0;
  bool         converged = false;
  for (; it < maximumIterations && !converged; ++it)
  {
    const Eigen::VectorXd g = J.transpose() * r + d.regularization * p;
    if (g.norm() <= tolerance * std::max(1.0, p.norm()))
    {
      result.stop = "gradient below tolerance";
      converged = true;
      break;
    }
    Eigen::MatrixXd H = J.transpose() * J;
    H.diagonal().array() += d.regularization;
    bool accepted = false;
    for (int attempt = 0; attempt < 30 && !accepted; ++attempt)
    {
      Eigen::MatrixXd M = H;
      // Marquardt scaling plus a floor of 1e-3 of the mean curvature: directions the objective hardly sees
      // (a wall sliding along itself) get short steps instead of huge rejected ones.
      M.diagonal().array() += mu * (H.diagonal().array() + 1e-3 * H.diagonal().mean());
      const Eigen::VectorXd delta = M.ldlt().solve(-g);
      const Eigen::VectorXd pTry = p + delta;
      const double          valueTry = residuals(pTry, rTry, nullptr);
      if (valueTry < value)
      {
        const double decrease = value - valueTry;
        p = pTry;
        value = residuals(p, r, &J);
        mu = std::max(mu / 3.0, 1e-9);
        accepted = true;
        if (decrease <= 1e-10 * value)
        {
          converged = true;
          result.stop = "no further decrease";
        }
      }
      else
      {
        mu *= 4.0;
      }
    }
    if (!accepted)
    {
      result.stop = "no descent";
      break;
    }
  }
  result.iterations = it;
  result.parameters.assign(p.data(), p.data() + np);
  result.value = Evaluate(result.parameters, &result.gradient, &result.logModulusGradient);
  return result;
}

} // namespace bmr

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
#include "bmrWallMotionBasis.h"

#include "bmrAtomicFile.h"
#include "bmrError.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

namespace bmr {
namespace {
using Json = nlohmann::json;
using Vector3 = Eigen::Vector3d;

constexpr const char * FormatName = "biomechreg-wall-motion-basis";

void
CheckFinite(const std::vector<double> & values, const char * what)
{
  for (double v : values)
  {
    if (!std::isfinite(v))
    {
      FailInput("WallMotionBasis", std::string("a value of ") + what + " is not finite");
    }
  }
}

/** The closest point to \a p on triangle (a, b, c) and its barycentric coordinates (Ericson, Real-Time Collision
 * Detection, 5.1.5: the Voronoi regions of the corners, the edges and the face in turn). */
Vector3
ClosestOnTriangle(const Vector3 & p, const Vector3 & a, const Vector3 & b, const Vector3 & c, Vector3 & weights)
{
  const Vector3 ab = b - a, ac = c - a, ap = p - a;
  const double  d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0)
  {
    weights = { 1.0, 0.0, 0.0 };
    return a;
  }
  const Vector3 bp = p - b;
  const double  d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3)
  {
    weights = { 0.0, 1.0, 0.0 };
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
  {
    const double v = d1 / (d1 - d3);
    weights = { 1.0 - v, v, 0.0 };
    return a + v * ab;
  }
  const Vector3 cp = p - c;
  const double  d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6)
  {
    weights = { 0.0, 0.0, 1.0 };
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
  {
    const double w = d2 / (d2 - d6);
    weights = { 1.0 - w, 0.0, w };
    return a + w * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
  {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    weights = { 0.0, 1.0 - w, w };
    return b + w * (c - b);
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  weights = { 1.0 - v - w, v, w };
  return a + ab * v + ac * w;
}

Vector3
PointOf(const WallMotionBasis & surface, std::int32_t i)
{
  return { surface.points[i][0], surface.points[i][1], surface.points[i][2] };
}

/** Where a point lies on a surface of walls: the three surface points of the closest triangle and their weights (or
 * the closest point, thrice, on a wall without triangles), and the distance [mm]. */
struct AtlasPosition
{
  std::array<std::int32_t, 3> corners{ 0, 0, 0 };
  Vector3                     weights{ 1.0, 0.0, 0.0 };
  double                      distance{ std::numeric_limits<double>::infinity() };
  std::size_t                 triangle{ std::numeric_limits<std::size_t>::max() };
};

/** \brief Finds the closest triangle of a wall of \a surface: the wall's triangles binned in a uniform grid of cells
 * twice their median edge, searched in rings of cells around the point until no farther ring can hold a closer one.
 * Ties go to the lowest triangle index, so the answer does not depend on the order the cells are visited in. */
class SurfaceLocator
{
public:
  explicit SurfaceLocator(const WallMotionBasis & surface)
    : m_Surface(surface)
    , m_Walls(surface.walls.size())
  {
    std::vector<double> edges;
    for (const auto & t : surface.triangles)
    {
      edges.push_back((PointOf(surface, t[0]) - PointOf(surface, t[1])).norm());
    }
    std::sort(edges.begin(), edges.end());
    m_Cell = std::max(0.5, edges.empty() ? 1.0 : 2.0 * edges[edges.size() / 2]);
    for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    {
      Bin(m_Walls[surface.pointWalls[surface.triangles[t][0]]], t);
    }
  }

  AtlasPosition
  Locate(const Vector3 & p, std::int32_t wall) const
  {
    const Wall & w = m_Walls[wall];
    if (w.cells.empty())
    {
      return ClosestPoint(p, wall);
    }
    AtlasPosition        best;
    const Eigen::Array3i home = CellOf(p);
    const int            reach = (home - w.lo).abs().max((home - w.hi).abs()).maxCoeff();
    for (int ring = 0; ring <= reach; ++ring)
    {
      VisitRing(w, home, ring, p, best);
      if (best.distance <= double(ring) * m_Cell)
      {
        break; // a cell of the next ring lies at least ring cells away
      }
    }
    return best;
  }

private:
  struct Wall
  {
    std::map<std::array<int, 3>, std::vector<std::size_t>> cells;
    Eigen::Array3i lo{ Eigen::Array3i::Constant(std::numeric_limits<int>::max()) };
    Eigen::Array3i hi{ Eigen::Array3i::Constant(std::numeric_limits<int>::min()) };
  };

  Eigen::Array3i
  CellOf(const Vector3 & p) const
  {
    return (p.array() / m_Cell).floor().cast<int>();
  }
  void
  Bin(Wall & w, std::size_t t)
  {
    const auto & tri = m_Surface.triangles[t];
    Vector3      lo = PointOf(m_Surface, tri[0]), hi = lo;
    for (int j = 1; j < 3; ++j)
    {
      lo = lo.cwiseMin(PointOf(m_Surface, tri[j]));
      hi = hi.cwiseMax(PointOf(m_Surface, tri[j]));
    }
    const Eigen::Array3i a = CellOf(lo), b = CellOf(hi);
    w.lo = w.lo.min(a);
    w.hi = w.hi.max(b);
    for (int i = a[0]; i <= b[0]; ++i)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int k = a[2]; k <= b[2]; ++k)
          w.cells[{ i, j, k }].push_back(t);
  }
  /** The triangles in the cells at Chebyshev distance \a ring from \a home (within the wall's cells). */
  void
  VisitRing(const Wall & w, const Eigen::Array3i & home, int ring, const Vector3 & p, AtlasPosition & best) const
  {
    const Eigen::Array3i lo = (home - ring).max(w.lo), hi = (home + ring).min(w.hi);
    for (int i = lo[0]; i <= hi[0]; ++i)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int k = lo[2]; k <= hi[2]; ++k)
        {
          const Eigen::Array3i c(i, j, k);
          const auto           found = w.cells.find({ i, j, k });
          if ((c - home).abs().maxCoeff() != ring || found == w.cells.end())
          {
            continue;
          }
          for (std::size_t t : found->second)
          {
            Consider(t, p, best);
          }
        }
  }
  void
  Consider(std::size_t t, const Vector3 & p, AtlasPosition & best) const
  {
    const auto & tri = m_Surface.triangles[t];
    Vector3      weights;
    const double d =
      (ClosestOnTriangle(
         p, PointOf(m_Surface, tri[0]), PointOf(m_Surface, tri[1]), PointOf(m_Surface, tri[2]), weights) -
       p)
        .norm();
    if (d < best.distance || (d == best.distance && t < best.triangle))
    {
      best = { tri, weights, d, t };
    }
  }
  /** A wall without triangles: its closest point. */
  AtlasPosition
  ClosestPoint(const Vector3 & p, std::int32_t wall) const
  {
    AtlasPosition best;
    for (std::size_t i = 0; i < m_Surface.points.size(); ++i)
    {
      const double d = (PointOf(m_Surface, static_cast<std::int32_t>(i)) - p).norm();
      if (m_Surface.pointWalls[i] == wall && d < best.distance)
      {
        const auto index = static_cast<std::int32_t>(i);
        best.corners = { index, index, index };
        best.distance = d;
      }
    }
    return best;
  }

  const WallMotionBasis & m_Surface;
  std::vector<Wall>       m_Walls;
  double                  m_Cell{ 1.0 };
};

/** \a field (3 per atlas point) at \a position. */
void
Interpolate(const std::vector<double> & field, const AtlasPosition & position, double * out)
{
  for (int c = 0; c < 3; ++c)
  {
    out[c] = 0.0;
    for (int j = 0; j < 3; ++j)
    {
      out[c] += position.weights[j] * field[3 * static_cast<std::size_t>(position.corners[j]) + c];
    }
  }
}
/** The point \a position stands for on \a surface. */
Vector3
ClosestPointOn(const WallMotionBasis & surface, const AtlasPosition & position)
{
  Vector3 p = Vector3::Zero();
  for (int j = 0; j < 3; ++j)
  {
    p += position.weights[j] * PointOf(surface, position.corners[j]);
  }
  return p;
}

/** Moves each wall's points \a x of \a atlas so that their centroid is that wall's in \a walls. */
void
MoveCentroids(const WallMotionBasis & atlas, const WallMotionBasis & walls, std::vector<Vector3> & x)
{
  const std::size_t    count = atlas.walls.size();
  std::vector<Vector3> from(count, Vector3::Zero()), to(count, Vector3::Zero());
  std::vector<double>  nFrom(count, 0.0), nTo(count, 0.0);
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    from[atlas.pointWalls[i]] += x[i];
    nFrom[atlas.pointWalls[i]] += 1.0;
  }
  for (std::size_t i = 0; i < walls.points.size(); ++i)
  {
    to[walls.pointWalls[i]] += PointOf(walls, static_cast<std::int32_t>(i));
    nTo[walls.pointWalls[i]] += 1.0;
  }
  for (std::size_t i = 0; i < x.size(); ++i)
  {
    const std::int32_t w = atlas.pointWalls[i];
    if (nTo[w] == 0.0)
    {
      FailInput("FitAtlasToWalls", "the walls to fit have no point on \"" + atlas.walls[w] + "\"");
    }
    x[i] += to[w] / nTo[w] - from[w] / nFrom[w];
  }
}

/** Each atlas point's neighbours on the atlas triangles, sorted. */
std::vector<std::vector<std::int32_t>>
Neighbours(const WallMotionBasis & atlas)
{
  std::vector<std::set<std::int32_t>> sets(atlas.points.size());
  for (const auto & t : atlas.triangles)
  {
    for (int a = 0; a < 3; ++a)
    {
      sets[t[a]].insert(t[(a + 1) % 3]);
      sets[t[a]].insert(t[(a + 2) % 3]);
    }
  }
  std::vector<std::vector<std::int32_t>> lists;
  for (const auto & set : sets)
  {
    lists.emplace_back(set.begin(), set.end());
  }
  return lists;
}
} // namespace

void
WallMotionBasis::Validate() const
{
  const std::size_t n = points.size();
  if (pointWalls.size() != n || mean.size() != 3 * n || variances.size() != modes.size() ||
      explainedVariance.size() != modes.size())
  {
    FailInput("WallMotionBasis", "the sizes of points, point walls, mean, modes and variances disagree");
  }
  for (std::int32_t w : pointWalls)
  {
    if (w < 0 || static_cast<std::size_t>(w) >= walls.size())
    {
      FailInput("WallMotionBasis", "a point's wall index is out of range");
    }
  }
  for (const auto & t : triangles)
  {
    for (std::int32_t i : t)
    {
      if (i < 0 || static_cast<std::size_t>(i) >= n)
      {
        FailInput("WallMotionBasis", "a triangle's point index is out of range");
      }
    }
  }
  CheckFinite(mean, "the mean");
  for (std::size_t k = 0; k < modes.size(); ++k)
  {
    if (modes[k].size() != 3 * n)
    {
      FailInput("WallMotionBasis", "a mode does not have 3 values per point");
    }
    CheckFinite(modes[k], "a mode");
    if (!(variances[k] > 0.0 && std::isfinite(variances[k])))
    {
      FailInput("WallMotionBasis", "a mode's variance is not positive");
    }
  }
}

WallMotionBasis
WallAtlas(const TetrahedralMesh & mesh, const std::vector<LoadedWall> & walls, std::vector<std::int32_t> * nodes)
{
  WallMotionBasis                      atlas;
  std::map<std::int32_t, std::int32_t> pointOfNode;
  for (std::size_t w = 0; w < walls.size(); ++w)
  {
    atlas.walls.push_back(walls[w].name);
    for (std::int32_t node : walls[w].nodes)
    {
      if (pointOfNode.emplace(node, static_cast<std::int32_t>(atlas.points.size())).second)
      {
        const double * x = &mesh.points[3 * static_cast<std::size_t>(node)];
        atlas.points.push_back({ x[0], x[1], x[2] });
        atlas.pointWalls.push_back(static_cast<std::int32_t>(w));
        if (nodes != nullptr)
        {
          nodes->push_back(node);
        }
      }
    }
  }
  for (std::size_t f = 0; f < mesh.boundaryFaceLabels.size(); ++f)
  {
    for (std::size_t w = 0; w < walls.size(); ++w)
    {
      std::array<std::int32_t, 3> triangle{};
      bool                        onWall = mesh.boundaryFaceLabels[f] == walls[w].faceLabel;
      for (int j = 0; j < 3 && onWall; ++j)
      {
        const auto it = pointOfNode.find(mesh.boundaryFaces[3 * f + j]);
        onWall = it != pointOfNode.end() && atlas.pointWalls[it->second] == static_cast<std::int32_t>(w);
        triangle[j] = onWall ? it->second : 0;
      }
      if (onWall)
      {
        atlas.triangles.push_back(triangle);
      }
    }
  }
  atlas.mean.assign(3 * atlas.points.size(), 0.0);
  return atlas;
}

WallMotionBasis
TrainWallMotionBasis(WallMotionBasis                          atlas,
                     const std::vector<std::vector<double>> & examples,
                     std::size_t                              maximumModes,
                     const std::string &                      training)
{
  const std::size_t n3 = 3 * atlas.points.size(), m = examples.size();
  if (m < 2 || n3 == 0)
  {
    FailInput("TrainWallMotionBasis", "a basis needs at least two examples on a non-empty atlas");
  }
  Eigen::MatrixXd X(n3, m);
  for (std::size_t i = 0; i < m; ++i)
  {
    if (examples[i].size() != n3)
    {
      FailInput("TrainWallMotionBasis", "an example does not have 3 values per atlas point");
    }
    CheckFinite(examples[i], "an example");
    X.col(static_cast<Eigen::Index>(i)) = Eigen::Map<const Eigen::VectorXd>(examples[i].data(), n3);
  }
  const Eigen::VectorXd mean = X.rowwise().mean();
  X.colwise() -= mean;
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(X, Eigen::ComputeThinU);
  const Eigen::VectorXd                variance = svd.singularValues().array().square() / double(m - 1);
  const double                         total = variance.sum();
  atlas.mean.assign(mean.data(), mean.data() + n3);
  atlas.modes.clear();
  atlas.variances.clear();
  atlas.explainedVariance.clear();
  double explained = 0.0;
  for (Eigen::Index k = 0; k < variance.size() && atlas.modes.size() < maximumModes; ++k)
  {
    if (!(variance[k] > 1e-12 * variance[0]))
    {
      break;
    }
    Eigen::VectorXd mode = svd.matrixU().col(k);
    Eigen::Index    largest = 0;
    mode.cwiseAbs().maxCoeff(&largest);
    if (mode[largest] < 0.0) // an SVD's signs are arbitrary: the largest component positive, the same every time
    {
      mode = -mode;
    }
    explained += variance[k];
    atlas.modes.emplace_back(mode.data(), mode.data() + n3);
    atlas.variances.push_back(variance[k]);
    atlas.explainedVariance.push_back(explained / total);
  }
  atlas.examples = m;
  atlas.training = training;
  atlas.Validate();
  return atlas;
}

void
WriteWallMotionBasis(const WallMotionBasis & basis, const std::string & path)
{
  basis.Validate();
  Json j;
  j["format"] = FormatName;
  j["version"] = 1;
  j["units"] = { { "points", "mm" }, { "mean", "mm" }, { "modes", "mm per unit p" }, { "variances", "mm^2" } };
  j["walls"] = basis.walls;
  j["points"] = basis.points;
  j["point_walls"] = basis.pointWalls;
  j["triangles"] = basis.triangles;
  j["mean"] = basis.mean;
  j["modes"] = basis.modes;
  j["variances"] = basis.variances;
  j["explained_variance"] = basis.explainedVariance;
  j["examples"] = basis.examples;
  j["training"] = basis.training;
  WriteTextFileAtomically(path, j.dump() + "\n");
}

WallMotionBasis
ReadWallMotionBasis(const std::string & path)
{
  std::ifstream in(path);
  if (!in)
  {
    FailInput("ReadWallMotionBasis", "cannot open the wall motion basis \"" + path + "\"");
  }
  WallMotionBasis basis;
  try
  {
    const Json j = Json::parse(in);
    if (j.at("format") != FormatName || j.at("version") != 1)
    {
      FailInput("ReadWallMotionBasis", "\"" + path + "\" is not a wall motion basis of version 1");
    }
    j.at("walls").get_to(basis.walls);
    j.at("points").get_to(basis.points);
    j.at("point_walls").get_to(basis.pointWalls);
    j.at("triangles").get_to(basis.triangles);
    j.at("mean").get_to(basis.mean);
    j.at("modes").get_to(basis.modes);
    j.at("variances").get_to(basis.variances);
    j.at("explained_variance").get_to(basis.explainedVariance);
    j.at("examples").get_to(basis.examples);
    j.at("training").get_to(basis.training);
  }
  catch (const Json::exception & e)
  {
    FailInput("ReadWallMotionBasis", "\"" + path + "\" is not a valid wall motion basis: " + e.what());
  }
  basis.Validate();
  return basis;
}

TransferredWallBasis
TransferWallMotionBasis(const WallMotionBasis &           basis,
                        std::size_t                       modes,
                        const std::vector<double> &       points,
                        const std::vector<std::int32_t> & pointWalls,
                        const std::vector<double> *       fittedAtlas)
{
  if (modes > basis.GetNumberOfModes() || points.size() != 3 * pointWalls.size())
  {
    FailInput("TransferWallMotionBasis", "more modes than the basis has, or not 3 coordinates per point");
  }
  WallMotionBasis where; // the surface the points are located on: the atlas, or the atlas fitted (geometry only)
  where.walls = basis.walls;
  where.points = basis.points;
  where.pointWalls = basis.pointWalls;
  where.triangles = basis.triangles;
  if (fittedAtlas != nullptr)
  {
    if (fittedAtlas->size() != 3 * basis.points.size())
    {
      FailInput("TransferWallMotionBasis", "the fitted atlas does not have 3 coordinates per atlas point");
    }
    for (std::size_t i = 0; i < basis.points.size(); ++i)
    {
      where.points[i] = { (*fittedAtlas)[3 * i], (*fittedAtlas)[3 * i + 1], (*fittedAtlas)[3 * i + 2] };
    }
  }
  const SurfaceLocator locator(where);
  const std::size_t    n = pointWalls.size();
  TransferredWallBasis out;
  out.mean.resize(3 * n);
  out.modes.assign(modes, std::vector<double>(3 * n));
  out.variances.assign(basis.variances.begin(), basis.variances.begin() + static_cast<std::ptrdiff_t>(modes));
  out.distances.resize(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::int32_t wall = pointWalls[i];
    if (wall < 0 || static_cast<std::size_t>(wall) >= basis.walls.size())
    {
      FailInput("TransferWallMotionBasis", "a point's wall is not one of the basis's walls");
    }
    const Vector3       p(points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    const AtlasPosition at = locator.Locate(p, wall);
    if (!std::isfinite(at.distance))
    {
      FailInput("TransferWallMotionBasis", "the basis has no point on the wall \"" + basis.walls[wall] + "\"");
    }
    out.distances[i] = at.distance;
    Interpolate(basis.mean, at, &out.mean[3 * i]);
    for (std::size_t k = 0; k < modes; ++k)
    {
      Interpolate(basis.modes[k], at, &out.modes[k][3 * i]);
    }
  }
  return out;
}

std::vector<double>
FitAtlasToWalls(const WallMotionBasis & basis, const WallMotionBasis & walls, unsigned int iterations)
{
  if (walls.walls != basis.walls)
  {
    FailInput("FitAtlasToWalls", "the walls to fit are not the atlas's walls (by name, in order)");
  }
  const std::size_t    n = basis.points.size();
  std::vector<Vector3> x(n);
  for (std::size_t i = 0; i < n; ++i)
  {
    x[i] = PointOf(basis, static_cast<std::int32_t>(i));
  }
  MoveCentroids(basis, walls, x);
  const std::vector<std::vector<std::int32_t>> neighbours = Neighbours(basis);
  const SurfaceLocator                         locator(walls);
  for (unsigned int round = 0; round <= iterations; ++round)
  {
    std::vector<Vector3> towards(n);
    double               largest = 0.0;
    for (std::size_t i = 0; i < n; ++i)
    {
      towards[i] = ClosestPointOn(walls, locator.Locate(x[i], basis.pointWalls[i])) - x[i];
      largest = std::max(largest, towards[i].norm());
    }
    for (std::size_t i = 0; i < n; ++i)
    {
      // The last round projects; the others slide the atlas as a sheet.
      Vector3 move = towards[i];
      if (round < iterations)
      {
        for (std::int32_t j : neighbours[i])
        {
          move += towards[j];
        }
        move /= double(neighbours[i].size() + 1);
      }
      x[i] += move;
    }
    if (largest == 0.0)
    {
      break; // on the walls already (an atlas fitted to its own walls)
    }
  }
  std::vector<double> fitted;
  fitted.reserve(3 * n);
  for (const Vector3 & p : x)
  {
    fitted.insert(fitted.end(), { p[0], p[1], p[2] });
  }
  return fitted;
}

} // namespace bmr

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
PointOf(const WallMotionBasis & basis, std::int32_t i)
{
  return { basis.points[i][0], basis.points[i][1], basis.points[i][2] };
}

/** Where point \a p of wall \a wall lies on the atlas: its three atlas points and their weights (the closest triangle
 * of the wall, or the closest point when the wall has no triangle), and the distance [mm]. */
struct AtlasPosition
{
  std::array<std::int32_t, 3> corners{ 0, 0, 0 };
  Vector3                     weights{ 1.0, 0.0, 0.0 };
  double                      distance{ std::numeric_limits<double>::infinity() };
};

AtlasPosition
Locate(const WallMotionBasis &          basis,
       const std::vector<std::size_t> & wallTriangles,
       const Vector3 &                  p,
       std::int32_t                     wall)
{
  AtlasPosition best;
  for (std::size_t t : wallTriangles)
  {
    const auto & tri = basis.triangles[t];
    Vector3      weights;
    const double d =
      (ClosestOnTriangle(p, PointOf(basis, tri[0]), PointOf(basis, tri[1]), PointOf(basis, tri[2]), weights) - p)
        .norm();
    if (d < best.distance)
    {
      best = { tri, weights, d };
    }
  }
  if (wallTriangles.empty())
  {
    for (std::size_t i = 0; i < basis.points.size(); ++i)
    {
      const double d = (PointOf(basis, static_cast<std::int32_t>(i)) - p).norm();
      if (basis.pointWalls[i] == wall && d < best.distance)
      {
        best.corners = { static_cast<std::int32_t>(i), static_cast<std::int32_t>(i), static_cast<std::int32_t>(i) };
        best.distance = d;
      }
    }
  }
  return best;
}

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
                        const std::vector<std::int32_t> & pointWalls)
{
  if (modes > basis.GetNumberOfModes() || points.size() != 3 * pointWalls.size())
  {
    FailInput("TransferWallMotionBasis", "more modes than the basis has, or not 3 coordinates per point");
  }
  std::vector<std::vector<std::size_t>> trianglesOfWall(basis.walls.size());
  for (std::size_t t = 0; t < basis.triangles.size(); ++t)
  {
    trianglesOfWall[basis.pointWalls[basis.triangles[t][0]]].push_back(t);
  }
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
    const AtlasPosition at = Locate(basis, trianglesOfWall[wall], p, wall);
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

} // namespace bmr

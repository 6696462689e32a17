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
#include "bmrMarkerAlignment.h"

#include "bmrError.h"

#include <Eigen/Dense>

#include <cmath>

namespace bmr {
namespace {
using Matrix3 = Eigen::Matrix3d;
using Vector3 = Eigen::Vector3d;

Vector3
ToEigen(const Point3 & p)
{
  return Vector3(p[0], p[1], p[2]);
}

void
CheckPairs(const std::vector<Point3> & from, const std::vector<Point3> & to, const char * where)
{
  if (from.empty() || from.size() != to.size())
  {
    Fail(where,
         "expected two equally long, non-empty marker lists, got " + std::to_string(from.size()) + " and " +
           std::to_string(to.size()));
  }
  for (const auto * list : { &from, &to })
  {
    for (const Point3 & p : *list)
    {
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      {
        Fail(where, "a marker coordinate is not finite");
      }
    }
  }
}

Vector3
Centroid(const std::vector<Point3> & points)
{
  Vector3 c = Vector3::Zero();
  for (const Point3 & p : points)
  {
    c += ToEigen(p);
  }
  return c / static_cast<double>(points.size());
}

/** The smallest rotation turning the unit vector \a a into the unit vector \a b (Rodrigues). */
Matrix3
SmallestRotation(const Vector3 & a, const Vector3 & b)
{
  const Vector3 axis = a.cross(b);
  const double  s = axis.norm(), c = a.dot(b);
  if (s < 1e-12)
  {
    if (c > 0.0)
    {
      return Matrix3::Identity();
    }
    // Half a turn about any axis normal to a.
    Vector3 normal = a.cross(std::abs(a.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY()).normalized();
    return 2.0 * normal * normal.transpose() - Matrix3::Identity();
  }
  Matrix3 k;
  k << 0, -axis.z(), axis.y(), axis.z(), 0, -axis.x(), -axis.y(), axis.x(), 0;
  return Matrix3::Identity() + k + k * k * ((1.0 - c) / (s * s));
}
} // namespace

Point3
RigidTransform::Apply(const Point3 & x) const
{
  Point3 y;
  for (int r = 0; r < 3; ++r)
  {
    y[r] = rotation[3 * r] * x[0] + rotation[3 * r + 1] * x[1] + rotation[3 * r + 2] * x[2] + translation[r];
  }
  return y;
}

Point3
RigidTransform::ApplyInverse(const Point3 & y) const
{
  const double d[3] = { y[0] - translation[0], y[1] - translation[1], y[2] - translation[2] };
  Point3       x;
  for (int c = 0; c < 3; ++c)
  {
    x[c] = rotation[c] * d[0] + rotation[3 + c] * d[1] + rotation[6 + c] * d[2];
  }
  return x;
}

RigidTransform
FitRigidTransform(const std::vector<Point3> & from, const std::vector<Point3> & to)
{
  CheckPairs(from, to, "FitRigidTransform");
  const Vector3 ca = Centroid(from), cb = Centroid(to);
  Matrix3       H = Matrix3::Zero();
  for (std::size_t k = 0; k < from.size(); ++k)
  {
    H += (ToEigen(from[k]) - ca) * (ToEigen(to[k]) - cb).transpose();
  }
  Eigen::JacobiSVD<Matrix3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vector3             sigma = svd.singularValues();
  Matrix3                   R = Matrix3::Identity();
  if (sigma(0) > 0.0 && sigma(1) > 1e-9 * sigma(0))
  {
    // The markers span a plane or more: the rotation is determined (Kabsch, without reflection).
    Matrix3 D = Matrix3::Identity();
    D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
    R = svd.matrixV() * D * svd.matrixU().transpose();
  }
  else if (sigma(0) > 0.0)
  {
    // Collinear markers: only the direction of their line is known.
    R = SmallestRotation(svd.matrixU().col(0), svd.matrixV().col(0));
  }
  RigidTransform t;
  const Vector3  translation = cb - R * ca;
  for (int r = 0; r < 3; ++r)
  {
    t.translation[r] = translation(r);
    for (int c = 0; c < 3; ++c)
    {
      t.rotation[3 * r + c] = R(r, c);
    }
  }
  return t;
}

ThinPlateSpline::ThinPlateSpline(const std::vector<Point3> & from, const std::vector<Point3> & to)
  : m_Centers(from)
{
  CheckPairs(from, to, "ThinPlateSpline");
  const auto    n = static_cast<Eigen::Index>(from.size());
  const Vector3 c = Centroid(from);
  m_Centroid = { { c.x(), c.y(), c.z() } };
  Eigen::MatrixXd system = Eigen::MatrixXd::Zero(n + 4, n + 4);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n + 4, 3);
  for (Eigen::Index j = 0; j < n; ++j)
  {
    for (Eigen::Index k = 0; k < n; ++k)
    {
      system(j, k) = (ToEigen(from[j]) - ToEigen(from[k])).norm();
      if (j != k && system(j, k) == 0.0)
      {
        Fail("ThinPlateSpline", "two markers coincide");
      }
    }
    const Vector3 local = ToEigen(from[j]) - c;
    system(j, n) = system(n, j) = 1.0;
    for (int d = 0; d < 3; ++d)
    {
      system(j, n + 1 + d) = system(n + 1 + d, j) = local(d);
    }
    rhs.row(j) = (ToEigen(to[j]) - ToEigen(from[j])).transpose();
  }
  const Eigen::MatrixXd solution = system.completeOrthogonalDecomposition().solve(rhs);
  for (Eigen::Index k = 0; k < n; ++k)
  {
    m_Weights.push_back({ { solution(k, 0), solution(k, 1), solution(k, 2) } });
  }
  for (int out = 0; out < 3; ++out)
  {
    for (int a = 0; a < 4; ++a)
    {
      m_Affine[4 * out + a] = solution(n + a, out);
    }
  }
}

Point3
ThinPlateSpline::Apply(const Point3 & x) const
{
  const double local[3] = { x[0] - m_Centroid[0], x[1] - m_Centroid[1], x[2] - m_Centroid[2] };
  Point3       y = x;
  for (int out = 0; out < 3; ++out)
  {
    const double * a = &m_Affine[4 * out];
    y[out] += a[0] + a[1] * local[0] + a[2] * local[1] + a[3] * local[2];
  }
  for (std::size_t k = 0; k < m_Centers.size(); ++k)
  {
    const double r = std::hypot(x[0] - m_Centers[k][0], x[1] - m_Centers[k][1], x[2] - m_Centers[k][2]);
    for (int out = 0; out < 3; ++out)
    {
      y[out] += m_Weights[k][out] * r;
    }
  }
  return y;
}

} // namespace bmr

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
// The trained wall basis (dissertation ch. 5): training, its file, its transfer to another mesh, and the loads that
// move the walls in it. What is checked, with the tolerance and why:
// - a basis trained on examples of exact rank 3 has 3 modes (the rest fall below 1e-12 of the largest variance),
//   orthonormal to 1e-12, its mean the examples' mean and every example rebuilt from the modes to 1e-10 mm (an SVD is
//   exact to rounding here), the explained variance reaching 1;
// - the file round-trips every number bit for bit (JSON doubles written with 17 digits); a missing file, a broken
//   one and inconsistent sizes are refused by name;
// - transferred to another mesh of the same walls, a mode that is an affine field on the atlas is carried to within
//   |A| times each node's distance to the atlas surface (barycentric interpolation reproduces an affine field on a
//   triangle exactly; what remains is the offset between the two meshes' surfaces), and on the atlas's own mesh
//   exactly (distances 0);
// - TrainedWallLoads: the prior w/2 sum p_k^2/lambda_k, the fit of a displacement in the basis p*/(1 + w/lambda_k)
//   (orthonormal modes; 1e-10), and the adjoint gradient of Phi + R by the Taylor test (slope 2).
#include "bmrSurfaceMatchingObjective.h"
#include "bmrTestUtilities.h"
#include "bmrTrainedWallLoads.h"

#include <Eigen/Dense>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;

/** The affine fields the examples are made of, at point x [mm]: a translation, a shear and a dilation about the
 * cavity's centre; and the examples' common offset. */
std::array<double, 3>
Pattern(int j, const std::array<double, 3> & x)
{
  switch (j)
  {
    case 0:
      return { 1.0, 0.0, 0.0 };
    case 1:
      return { 0.0, 0.0, 0.1 * x[0] };
    case 2:
      return { 0.1 * (x[0] + 6.0), 0.1 * x[1], 0.1 * x[2] };
    default:
      return { 0.02 * x[1], 0.3, 0.0 };
  }
}

/** 8 examples on \a atlas: the offset plus random multiples of the three patterns. */
std::vector<std::vector<double>>
RankThreeExamples(const bmr::WallMotionBasis & atlas)
{
  std::mt19937_64                  rng(7);
  std::vector<std::vector<double>> examples;
  for (int i = 0; i < 8; ++i)
  {
    const double        c[3] = { double(rng() % 1000) / 500.0 - 1.0,
                                 double(rng() % 1000) / 500.0 - 1.0,
                                 double(rng() % 1000) / 500.0 - 1.0 };
    std::vector<double> x;
    for (const auto & point : atlas.points)
    {
      for (int d = 0; d < 3; ++d)
      {
        x.push_back(Pattern(3, point)[d] + c[0] * Pattern(0, point)[d] + c[1] * Pattern(1, point)[d] +
                    c[2] * Pattern(2, point)[d]);
      }
    }
    examples.push_back(x);
  }
  return examples;
}

bool
CheckTraining(const bmr::WallMotionBasis & basis, const std::vector<std::vector<double>> & examples)
{
  const std::size_t n3 = basis.mean.size();
  double            orthonormality = 0.0, rebuilt = 0.0, mean = 0.0;
  for (std::size_t k = 0; k < basis.GetNumberOfModes(); ++k)
  {
    for (std::size_t l = 0; l < basis.GetNumberOfModes(); ++l)
    {
      double dot = 0.0;
      for (std::size_t i = 0; i < n3; ++i)
      {
        dot += basis.modes[k][i] * basis.modes[l][i];
      }
      orthonormality = std::max(orthonormality, std::abs(dot - (k == l ? 1.0 : 0.0)));
    }
  }
  for (std::size_t i = 0; i < n3; ++i)
  {
    double sum = 0.0;
    for (const auto & x : examples)
    {
      sum += x[i];
    }
    mean = std::max(mean, std::abs(sum / double(examples.size()) - basis.mean[i]));
  }
  for (const auto & x : examples)
  {
    std::vector<double> y = basis.mean;
    for (const auto & mode : basis.modes)
    {
      double p = 0.0;
      for (std::size_t i = 0; i < n3; ++i)
      {
        p += mode[i] * (x[i] - basis.mean[i]);
      }
      for (std::size_t i = 0; i < n3; ++i)
      {
        y[i] += p * mode[i];
      }
    }
    for (std::size_t i = 0; i < n3; ++i)
    {
      rebuilt = std::max(rebuilt, std::abs(y[i] - x[i]));
    }
  }
  std::cout << "trained: " << basis.GetNumberOfModes() << " modes, variances";
  for (double v : basis.variances)
  {
    std::cout << " " << v;
  }
  std::cout << " mm^2; orthonormality " << orthonormality << ", mean " << mean << ", rebuilt " << rebuilt << " mm"
            << std::endl;
  bool ok = Expect(basis.GetNumberOfModes() == 3, "examples of rank 3 give 3 modes");
  ok &= Expect(orthonormality < 1e-12, "the modes are orthonormal to 1e-12");
  ok &= Expect(mean < 1e-12, "the mean is the examples' mean to 1e-12 mm");
  ok &= Expect(rebuilt < 1e-10, "every example is rebuilt from the modes to 1e-10 mm");
  ok &= Expect(std::abs(basis.explainedVariance.back() - 1.0) < 1e-12 && basis.examples == examples.size(),
               "the explained variance reaches 1 and the basis counts its examples");
  return ok;
}

bool
CheckFile(const bmr::WallMotionBasis & basis)
{
  const std::string path = (std::filesystem::temp_directory_path() / "bmrWallMotionBasisTest.json").string();
  bmr::WriteWallMotionBasis(basis, path);
  const bmr::WallMotionBasis read = bmr::ReadWallMotionBasis(path);
  bool ok = Expect(read.walls == basis.walls && read.points == basis.points && read.pointWalls == basis.pointWalls &&
                     read.triangles == basis.triangles && read.mean == basis.mean && read.modes == basis.modes &&
                     read.variances == basis.variances && read.explainedVariance == basis.explainedVariance &&
                     read.examples == basis.examples && read.training == basis.training,
                   "the basis round-trips through its file bit for bit");
  std::ofstream(path) << "{\"format\": \"biomechreg-wall-motion-basis\", \"version\": 1, \"walls\": [";
  ok &= bmr::test::ExpectException(
    "a broken file", [&] { bmr::ReadWallMotionBasis(path); }, "is not a valid wall motion basis");
  std::filesystem::remove(path);
  ok &= bmr::test::ExpectException(
    "a missing file", [&] { bmr::ReadWallMotionBasis(path); }, "cannot open the wall motion basis");
  bmr::WallMotionBasis inconsistent = basis;
  inconsistent.variances.pop_back();
  ok &= bmr::test::ExpectException(
    "inconsistent sizes", [&] { bmr::WriteWallMotionBasis(inconsistent, path); }, "sizes");
  return ok;
}

/** The affine field (A, b) that \a values (3 per point) are on \a basis's atlas points: least squares, exact here. */
Eigen::Matrix<double, 3, 4>
AffineFit(const bmr::WallMotionBasis & basis, const std::vector<double> & values)
{
  Eigen::MatrixXd X(basis.points.size(), 4);
  Eigen::MatrixXd Y(basis.points.size(), 3);
  for (std::size_t i = 0; i < basis.points.size(); ++i)
  {
    X.row(i) << basis.points[i][0], basis.points[i][1], basis.points[i][2], 1.0;
    Y.row(i) << values[3 * i], values[3 * i + 1], values[3 * i + 2];
  }
  return X.colPivHouseholderQr().solve(Y).transpose();
}

bool
CheckTransfer(const bmr::WallMotionBasis & basis, const bmr::Scene & scene)
{
  const bmr::TetrahedralMesh other = bmr::test::CavityInclusionBall(2.5); // the same walls, meshed anew
  std::vector<std::int32_t>  nodes;
  const bmr::WallMotionBasis otherAtlas = bmr::WallAtlas(other, bmr::SceneLoadedWalls(scene, other), &nodes);
  std::vector<double>        points;
  for (const auto & p : otherAtlas.points)
  {
    points.insert(points.end(), p.begin(), p.end());
  }
  const bmr::TransferredWallBasis carried = bmr::TransferWallMotionBasis(basis, 3, points, otherAtlas.pointWalls);
  double                          worstExcess = 0.0, farthest = 0.0;
  for (std::size_t k = 0; k < 3; ++k)
  {
    const Eigen::Matrix<double, 3, 4> field = AffineFit(basis, basis.modes[k]);
    const double                      slope = field.leftCols<3>().norm(); // bounds |A| in the 2-norm
    for (std::size_t i = 0; i < otherAtlas.points.size(); ++i)
    {
      const Eigen::Vector4d x(points[3 * i], points[3 * i + 1], points[3 * i + 2], 1.0);
      const Eigen::Vector3d exact = field * x;
      const Eigen::Vector3d got(carried.modes[k][3 * i], carried.modes[k][3 * i + 1], carried.modes[k][3 * i + 2]);
      worstExcess = std::max(worstExcess, (got - exact).norm() - slope * carried.distances[i]);
      farthest = std::max(farthest, carried.distances[i]);
    }
  }
  std::cout << "transfer to a new mesh: " << points.size() / 3 << " points, farthest from the atlas " << farthest
            << " mm, worst error beyond |A| distance " << worstExcess << " mm" << std::endl;
  bool ok = Expect(worstExcess < 1e-9, "an affine mode is carried to within |A| times the distance to the atlas");
  ok &= Expect(farthest < 1.0, "the new mesh's wall lies within 1 mm of the atlas (both within 0.5 mm of the sphere)");
  return ok;
}

/** The atlas fitted to another patient's walls: the same cavity scaled by 1.2 about its centre and moved by
 * (2, 1, -1) mm, meshed anew. Every fitted atlas point lies on the new walls (the last round projects; 1e-9 mm) and
 * within half an edge of the new mesh (1.5 mm) of the affine image of its atlas point, so that it takes its values
 * from the element it corresponds to; the rounds do not leave the correspondence worse (RMS) than the projection
 * alone. Fitted to its own walls, the atlas stays where it is, bit for bit. */
bool
CheckAtlasFit(const bmr::WallMotionBasis & basis, const bmr::Scene & scene)
{
  const Eigen::Vector3d centre(-6.0, 0.0, 0.0), shift(2.0, 1.0, -1.0);
  const auto image = [&](const Eigen::Vector3d & x) -> Eigen::Vector3d { return centre + 1.2 * (x - centre) + shift; };
  bmr::TetrahedralMesh other = bmr::test::CavityInclusionBall(2.5);
  for (std::size_t i = 0; i < other.GetNumberOfPoints(); ++i)
  {
    const Eigen::Vector3d x = image({ other.points[3 * i], other.points[3 * i + 1], other.points[3 * i + 2] });
    std::copy_n(x.data(), 3, &other.points[3 * i]);
  }
  const bmr::WallMotionBasis walls = bmr::WallAtlas(other, bmr::SceneLoadedWalls(scene, other));
  const auto                 rmsFromImage = [&](const std::vector<double> & fitted, double & largest) {
    double squares = 0.0;
    for (std::size_t i = 0; i < basis.points.size(); ++i)
    {
      const Eigen::Vector3d x(fitted[3 * i], fitted[3 * i + 1], fitted[3 * i + 2]);
      const Eigen::Vector3d atlasPoint(basis.points[i][0], basis.points[i][1], basis.points[i][2]);
      largest = std::max(largest, (x - image(atlasPoint)).norm());
      squares += (x - image(atlasPoint)).squaredNorm();
    }
    return std::sqrt(squares / double(basis.points.size()));
  };
  const std::vector<double> fitted = bmr::FitAtlasToWalls(basis, walls);
  double                    fromImage = 0.0, projectedLargest = 0.0, offSurface = 0.0;
  const double              rms = rmsFromImage(fitted, fromImage);
  const double              projectedRms = rmsFromImage(bmr::FitAtlasToWalls(basis, walls, 0), projectedLargest);
  const auto                carried = bmr::TransferWallMotionBasis(walls, 0, fitted, basis.pointWalls);
  for (double d : carried.distances)
  {
    offSurface = std::max(offSurface, d);
  }
  const std::vector<double> own =
    bmr::FitAtlasToWalls(basis,
                         bmr::WallAtlas(bmr::test::CavityInclusionBall(3.0),
                                        bmr::SceneLoadedWalls(scene, bmr::test::CavityInclusionBall(3.0))));
  bool stays = true;
  for (std::size_t i = 0; i < basis.points.size(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      stays = stays && own[3 * i + c] == basis.points[i][c];
    }
  }
  std::cout << "atlas fitted to a scaled, moved cavity: off its walls " << offSurface << " mm, from the affine image "
            << fromImage << " mm at most, " << rms << " mm RMS (projection alone: " << projectedLargest << ", "
            << projectedRms << " mm)" << std::endl;
  bool ok = Expect(offSurface < 1e-9, "the fitted atlas lies on the other walls");
  ok &= Expect(fromImage < 1.5, "each fitted atlas point lies within half an edge (1.5 mm) of its affine image");
  ok &= Expect(rms <= projectedRms, "the sheet's rounds leave the correspondence no worse than the projection alone");
  ok &= Expect(stays, "an atlas fitted to its own walls stays where it is, bit for bit");
  return ok;
}

bool
CheckLoads(const bmr::TetrahedralMesh & mesh, const bmr::Scene & scene, const bmr::WallMotionBasis & basis)
{
  bmr::WallLoadSettings settings;
  settings.trainedBasis = std::make_shared<const bmr::WallMotionBasis>(basis);
  settings.basisPriorWeight = 0.25;
  const double center[3] = { -6.0, 0.0, 0.0 }, moved[3] = { 7.0, 0.5, 0.0 };
  std::map<std::int32_t, std::shared_ptr<const bmr::SignedDistanceSampler>> maps{
    { 2, bmr::test::SphereSampler(moved, 5.0) }, { 3, bmr::test::SphereSampler(center, 7.5) }
  };
  bmr::SurfaceMatchingObjective objective(mesh, scene, bmr::SceneObjectiveSurfaces(scene, mesh, maps), settings);
  const auto &                  loads = dynamic_cast<const bmr::TrainedWallLoads &>(objective.GetLoads());
  bool   ok = Expect(loads.GetNumberOfParameters() == 3 && loads.IsReducedBasis(), "three parameters, reduced");
  double farthest = 0.0;
  for (double d : loads.GetTransferDistances())
  {
    farthest = std::max(farthest, d);
  }
  ok &= Expect(farthest == 0.0, "on the atlas's own mesh the basis applies exactly (distance 0)");
  ok &= Expect(std::abs(loads.EvaluatePrior({ 0.0, 2.0, 0.0 }) - 0.5 * 0.25 * 4.0 / basis.variances[1]) < 1e-15,
               "the prior is w/2 p_k^2/lambda_k");
  // A displacement in the basis, p* = (0.7, -0.4, 0.2), is fitted as p*_k / (1 + w / lambda_k).
  const std::vector<double> pStar = { 0.7, -0.4, 0.2 };
  const std::vector<double> u = loads.Apply(pStar).prescribed;
  const std::vector<double> fit = loads.FitDisplacement(u);
  double                    worst = 0.0;
  for (std::size_t k = 0; k < 3; ++k)
  {
    worst = std::max(worst, std::abs(fit[k] - pStar[k] / (1.0 + 0.25 / basis.variances[k])));
  }
  ok &=
    Expect(worst < 1e-10, "the fit of a displacement in the basis is p*/(1 + w/lambda) (got " + ToString(worst) + ")");
  objective.SetYoungsModuli({ 40.0 });
  const std::vector<double> p = objective.EstimateInitialParameters();
  std::vector<double>       gradient;
  const double              phi0 = objective.Evaluate(p, &gradient, nullptr);
  const std::vector<double> direction = { 0.6, -0.3, 0.8 };
  double                    slope = 0.0;
  for (std::size_t k = 0; k < 3; ++k)
  {
    slope += gradient[k] * direction[k];
  }
  ok &= bmr::test::CheckTaylor(
    "trained wall parameters",
    [&](double h) {
      std::vector<double> q = p;
      for (std::size_t k = 0; k < 3; ++k)
      {
        q[k] += h * direction[k];
      }
      return objective.Evaluate(q, nullptr, nullptr);
    },
    phi0,
    slope,
    0.5);
  return ok;
}
} // namespace

int
bmrWallMotionBasisTest(int, char *[])
{
  const bmr::TetrahedralMesh mesh = bmr::test::CavityInclusionBall(3.0);
  const bmr::Scene           scene = bmr::test::CavityInclusionScene(true);
  const bmr::WallMotionBasis atlas = bmr::WallAtlas(mesh, bmr::SceneLoadedWalls(scene, mesh));
  std::cout << "atlas: " << atlas.points.size() << " points, " << atlas.triangles.size() << " triangles" << std::endl;
  const auto                 examples = RankThreeExamples(atlas);
  const bmr::WallMotionBasis basis = bmr::TrainWallMotionBasis(atlas, examples, 10, "rank-3 test examples");
  bool                       ok = CheckTraining(basis, examples);
  ok &= CheckFile(basis);
  ok &= CheckTransfer(basis, scene);
  ok &= CheckAtlasFit(basis, scene);
  ok &= CheckLoads(mesh, scene, basis);
  ok &= bmr::test::ExpectException(
    "one example", [&] { bmr::TrainWallMotionBasis(atlas, { examples[0] }, 10, ""); }, "at least two examples");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

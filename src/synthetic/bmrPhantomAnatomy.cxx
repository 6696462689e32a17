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
// The phantoms' anatomy: pelvis organs and seeds, label functions, pelvis clearances and filling loads.
#include "bmrPhantom.h"

#include "bmrError.h"
#include "bmrPhantomModels.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

namespace bmr {
namespace phantom {
namespace {
/** \name Seed placement rules. The surface margin keeps every seed inside the
 * prostate label even after resampling; the spacing mimics clinical implants,
 * where seeds are separated by about a needle spacing.
 * \{ */
constexpr double SeedSurfaceMargin = 2.0;
constexpr double SeedMinCenterDistance = 6.0;
constexpr double SeedMinAxisDistance = 2.0;
constexpr double SeedMaxTiltDegrees = 20.0;
constexpr double SeedLength = 8.0;
constexpr double SeedDiameter = 1.5;
/** \} */

/** Shortest distance between segments [p0, p1] and [q0, q1] (clamped
 * closest-point parameters). Used to keep tilted seeds from touching even when
 * their centers are far enough apart. */
double
SegmentDistance(const Vec3 & p0, const Vec3 & p1, const Vec3 & q0, const Vec3 & q1)
{
  const Vec3   u = Subtract(p1, p0);
  const Vec3   v = Subtract(q1, q0);
  const Vec3   w = Subtract(p0, q0);
  const double a = Dot(u, u);
  const double b = Dot(u, v);
  const double c = Dot(v, v);
  const double d = Dot(u, w);
  const double e = Dot(v, w);
  const double denominator = a * c - b * b;

  double s = 0.0;
  if (denominator > 1e-12 * a * c)
  {
    s = std::clamp((b * e - c * d) / denominator, 0.0, 1.0);
  }
  double t = (b * s + e) / c;
  if (t < 0.0)
  {
    t = 0.0;
    s = std::clamp(-d / a, 0.0, 1.0);
  }
  else if (t > 1.0)
  {
    t = 1.0;
    s = std::clamp((b - d) / a, 0.0, 1.0);
  }
  const Vec3 closest = Subtract(Add(w, Scale(u, s)), Scale(v, t));
  return std::sqrt(Dot(closest, closest));
}

/** Refuses, before any rejection sampling, a number of seeds that cannot fit at least SeedMinCenterDistance apart
 * in the box of the admissible centres (those at most \a maxLevel of the prostate's level function). */
void
CheckSeedPacking(unsigned int numberOfSeeds, const Vec3 & semiAxes, double maxLevel)
{
  // Packing bound: the balls of radius SeedMinCenterDistance / 2 around the
  // centers are disjoint and lie in the box that bounds the admissible centers
  // grown by that radius. Refusing impossible requests here avoids spending
  // seconds in rejection sampling before failing.
  const double ballRadius = 0.5 * SeedMinCenterDistance;
  double       boxVolume = 1.0;
  for (unsigned int a = 0; a < 3; ++a)
  {
    boxVolume *= 2.0 * (maxLevel * semiAxes[a] + ballRadius);
  }
  const double maximumNumberOfSeeds = std::floor(boxVolume / (4.0 / 3.0 * Pi * ballRadius * ballRadius * ballRadius));
  if (static_cast<double>(numberOfSeeds) > maximumNumberOfSeeds)
  {
    std::ostringstream os;
    os << "cannot place " << numberOfSeeds << " seeds inside the prostate at least " << SeedMinCenterDistance
       << " mm apart (at most " << maximumNumberOfSeeds << " could fit)";
    Fail("MakePelvisPhantom", os.str());
  }
}

/** Whether a seed of centre \a center and axis [end0, end1] keeps its distances to the seeds placed so far. */
bool
FarFromPlacedSeeds(const Vec3 &                               center,
                   const Vec3 &                               end0,
                   const Vec3 &                               end1,
                   const std::vector<Vec3> &                  centers,
                   const std::vector<std::pair<Vec3, Vec3>> & axes)
{
  bool farEnough = true;
  for (std::size_t s = 0; s < centers.size() && farEnough; ++s)
  {
    const Vec3 d = Subtract(center, centers[s]);
    farEnough = std::sqrt(Dot(d, d)) >= SeedMinCenterDistance &&
                SegmentDistance(end0, end1, axes[s].first, axes[s].second) >= SeedMinAxisDistance;
  }
  return farEnough;
}
} // namespace

/** The organs of \a anatomy. A larger prostate pushes the bladder up and the rectum back by as much as it grows
 * towards them, so the soft tissue between the organs keeps about its default thickness; a larger bladder also
 * moves up (its bottom stays where it was) and pushes the rectum back by its posterior growth. */
OrganGeometry
Organs(const PelvisAnatomy & anatomy)
{
  const double  sp = anatomy.prostateScale;
  const double  sb = anatomy.bladderScale;
  const Vec3 &  d = anatomy.offset;
  OrganGeometry g;
  g.prostateCenter = Add(ProstateCenter, d);
  g.prostateSemiAxes = Scale(ProstateSemiAxes, sp);
  g.bladderCenter = Add(
    BladderCenter, Vec3{ { d[0], d[1], d[2] + ProstateSemiAxes[2] * (sp - 1.0) + BladderSemiAxes[2] * (sb - 1.0) } });
  g.bladderSemiAxes = Scale(BladderSemiAxes, sb);
  g.rectumRadius = anatomy.rectumRadius;
  g.rectumAxisX = d[0];
  g.rectumAxisY = RectumAxisY + d[1] + std::max(ProstateSemiAxes[1] * (sp - 1.0), BladderSemiAxes[1] * (sb - 1.0)) +
                  (anatomy.rectumRadius - RectumRadius);
  g.rectumTopZ = RectumTopZ + d[2] + ProstateSemiAxes[2] * (sp - 1.0);
  return g;
}

/** Places the seeds by rejection sampling inside the prostate.
 *
 * A seed is accepted when both end points of its axis satisfy
 * Level <= 1 - (margin + radius) / minSemiAxis. Because the level function is
 * convex and 1/minSemiAxis-Lipschitz, that keeps the whole capsule around the
 * axis (which contains the cylinder) at least \c margin from the prostate
 * surface, without computing true ellipsoid distances. */
std::vector<Seed>
PlaceSeeds(const Vec3 &          phantomCenter,
           const OrganGeometry & organs,
           unsigned int          numberOfSeeds,
           std::uint64_t         randomSeed)
{
  std::vector<Seed> seeds;
  if (numberOfSeeds == 0)
  {
    return seeds;
  }
  const Vec3 &    semiAxes = organs.prostateSemiAxes;
  const Ellipsoid prostate(organs.prostateCenter, semiAxes);
  const double    minSemiAxis = std::min({ semiAxes[0], semiAxes[1], semiAxes[2] });
  const double    maxLevel = 1.0 - (SeedSurfaceMargin + 0.5 * SeedDiameter) / minSemiAxis;
  const double    cosMaxTilt = std::cos(SeedMaxTiltDegrees * Pi / 180.0);

  CheckSeedPacking(numberOfSeeds, semiAxes, maxLevel);

  SplitMix64                         rng(randomSeed);
  std::vector<std::pair<Vec3, Vec3>> axes; // end points, relative to the phantom center
  std::vector<Vec3>                  centers;
  const unsigned long long           maximumAttempts = 2000ULL * (numberOfSeeds + 10ULL);
  unsigned long long                 attempts = 0;
  while (seeds.size() < numberOfSeeds && attempts < maximumAttempts)
  {
    ++attempts;
    Vec3 center{};
    for (unsigned int a = 0; a < 3; ++a)
    {
      center[a] = organs.prostateCenter[a] + (2.0 * rng.Uniform() - 1.0) * semiAxes[a];
    }
    // cos(tilt) uniform in [cos(max tilt), 1] spreads the axes uniformly over
    // the spherical cap around +z.
    const double cosTilt = 1.0 - rng.Uniform() * (1.0 - cosMaxTilt);
    const double sinTilt = std::sqrt(std::max(0.0, 1.0 - cosTilt * cosTilt));
    const double azimuth = 2.0 * Pi * rng.Uniform();
    const Vec3   axis{ { sinTilt * std::cos(azimuth), sinTilt * std::sin(azimuth), cosTilt } };

    const Vec3 end0 = Subtract(center, Scale(axis, 0.5 * SeedLength));
    const Vec3 end1 = Add(center, Scale(axis, 0.5 * SeedLength));
    if (prostate.Level(end0) > maxLevel || prostate.Level(end1) > maxLevel)
    {
      continue;
    }
    if (!FarFromPlacedSeeds(center, end0, end1, centers, axes))
    {
      continue;
    }
    centers.push_back(center);
    axes.emplace_back(end0, end1);
    Seed seed;
    seed.center = Add(phantomCenter, center);
    seed.axis = axis;
    seed.length = SeedLength;
    seed.diameter = SeedDiameter;
    seeds.push_back(seed);
  }
  if (seeds.size() < numberOfSeeds)
  {
    std::ostringstream os;
    os << "could not place " << numberOfSeeds << " seeds inside the prostate at least " << SeedMinCenterDistance
       << " mm apart (placed " << seeds.size() << " in " << attempts << " attempts)";
    Fail("MakePelvisPhantom", os.str());
  }
  return seeds;
}

} // namespace phantom

namespace {
using phantom::AxisAlignedCenteredGrid;
using phantom::CheckPhantomGrid;
using phantom::OrganGeometry;
using phantom::Organs;
using phantom::PelvisModel;
using phantom::PhantomCenter;
using phantom::PlaceSeeds;
using phantom::SphereModel;
using phantom::Vec3;

std::vector<std::int32_t>
LabelsAt(const PhantomLabelFunction & labelAt, const std::vector<double> & points, const char * where)
{
  if (points.size() % 3 != 0)
  {
    Fail(where, "expected 3 coordinates per point");
  }
  std::vector<std::int32_t> labels(points.size() / 3);
  for (std::size_t n = 0; n < labels.size(); ++n)
  {
    labels[n] = labelAt(points[3 * n], points[3 * n + 1], points[3 * n + 2]);
  }
  return labels;
}
} // namespace

PhantomLabelFunction
PelvisLabelFunction(const PelvisPhantomParameters & parameters)
{
  const char * where = "PelvisLabelFunction";
  CheckPhantomGrid(parameters.grid, "pelvis phantom grid", where);
  const Vec3          center = PhantomCenter(parameters.grid, parameters.useGridCenter, parameters.center, where);
  const OrganGeometry organs = Organs(parameters.anatomy);
  const auto          model = std::make_shared<const PelvisModel>(
    center, organs, PlaceSeeds(center, organs, parameters.numberOfSeeds, parameters.seedPlacementSeed));
  return [model](double x, double y, double z) { return PelvisModel::Label(model->Classify({ { x, y, z } })); };
}

std::vector<std::int32_t>
PelvisLabelsAt(const PelvisPhantomParameters & parameters, const std::vector<double> & points)
{
  return LabelsAt(PelvisLabelFunction(parameters), points, "PelvisLabelsAt");
}

namespace {
/** Offsets of the voxels within \a radius voxels of the origin, nearest first. */
std::vector<std::array<int, 4>>
BallOffsets(int radius)
{
  std::vector<std::array<int, 4>> ball; // dx, dy, dz, squared length
  for (int z = -radius; z <= radius; ++z)
    for (int y = -radius; y <= radius; ++y)
      for (int x = -radius; x <= radius; ++x)
      {
        const int d2 = x * x + y * y + z * z;
        if (d2 > 0 && d2 <= radius * radius)
        {
          ball.push_back({ { x, y, z, d2 } });
        }
      }
  std::stable_sort(ball.begin(), ball.end(), [](const auto & a, const auto & b) { return a[3] < b[3]; });
  return ball;
}

const char *
PelvisLabelName(std::int32_t label)
{
  switch (label)
  {
    case PelvisProstate:
      return "prostate";
    case PelvisBladder:
      return "bladder";
    case PelvisRectum:
      return "rectum";
    case PelvisBone:
      return "bone";
    default:
      return "body outline";
  }
}
} // namespace

PelvisClearance
MeasurePelvisClearance(const PelvisAnatomy & anatomy)
{
  constexpr int           Reach = 6; // mm = voxels
  PelvisPhantomParameters parameters;
  parameters.grid = AxisAlignedCenteredGrid({ { 172, 132, 150 } }, { { 1.0, 1.0, 1.0 } });
  parameters.numberOfSeeds = 0;
  parameters.anatomy = anatomy;
  const PhantomVolume                   volume = MakePelvisPhantom(parameters);
  const std::array<std::size_t, 3> &    n = volume.grid.size;
  const std::vector<std::array<int, 4>> ball = BallOffsets(Reach);
  const auto isOrgan = [](std::int32_t l) { return l == PelvisProstate || l == PelvisBladder || l == PelvisRectum; };
  PelvisClearance clearance;
  double          organ2 = Reach * Reach, other2 = Reach * Reach;
  for (std::size_t z = 0; z < n[2]; ++z)
    for (std::size_t y = 0; y < n[1]; ++y)
      for (std::size_t x = 0; x < n[0]; ++x)
      {
        const std::int32_t own = volume.labels[x + n[0] * (y + n[1] * z)];
        if (!isOrgan(own))
        {
          continue;
        }
        // The nearest voxel of another structure within reach; soft tissue and the grid's edge do not count.
        for (const auto & o : ball)
        {
          if (o[3] >= std::max(organ2, other2))
          {
            break;
          }
          const long X = long(x) + o[0], Y = long(y) + o[1], Z = long(z) + o[2];
          if (X < 0 || Y < 0 || Z < 0 || X >= long(n[0]) || Y >= long(n[1]) || Z >= long(n[2]))
          {
            continue;
          }
          const std::int32_t other = volume.labels[std::size_t(X) + n[0] * (std::size_t(Y) + n[1] * std::size_t(Z))];
          if (other == own || other == PelvisSoftTissue)
          {
            continue;
          }
          const std::string pair = std::string(PelvisLabelName(own)) + "-" + PelvisLabelName(other);
          if (isOrgan(other) && o[3] < organ2)
          {
            organ2 = o[3];
            clearance.closestOrgans = pair;
          }
          else if (!isOrgan(other) && o[3] < other2)
          {
            other2 = o[3];
            clearance.closestToBoneOrOutline = pair;
          }
        }
      }
  clearance.organToOrgan = std::sqrt(organ2);
  clearance.organToBoneOrOutline = std::sqrt(other2);
  return clearance;
}

PhantomLabelFunction
SphereLabelFunction(const SpherePhantomParameters & parameters)
{
  const Vec3 center =
    PhantomCenter(parameters.grid, parameters.useGridCenter, parameters.center, "SphereLabelFunction");
  const auto model = std::make_shared<const SphereModel>(center, parameters.innerRadius, parameters.outerRadius);
  return [model](double x, double y, double z) { return SphereModel::Label(model->Classify({ { x, y, z } })); };
}

std::vector<std::int32_t>
SphereLabelsAt(const SpherePhantomParameters & parameters, const std::vector<double> & points)
{
  return LabelsAt(SphereLabelFunction(parameters), points, "SphereLabelsAt");
}

std::vector<SceneLoad>
PelvisFillingLoads(const PelvisPhantomParameters & parameters,
                   double                          bladderMM,
                   double                          rectumMM,
                   WallFillingEnum                 filling)
{
  const Vec3 c = PhantomCenter(parameters.grid, parameters.useGridCenter, parameters.center, "PelvisFillingLoads");
  const auto at = [&c](const Vec3 & offset) {
    return Vec3{ { c[0] + offset[0], c[1] + offset[1], c[2] + offset[2] } };
  };
  const OrganGeometry    organs = Organs(parameters.anatomy);
  std::vector<SceneLoad> loads = {
    { "bladder", SceneLoad::TypeEnum::RadialDisplacement, at(organs.bladderCenter), bladderMM },
    { "rectum",
      SceneLoad::TypeEnum::RadialDisplacement,
      at({ { organs.rectumAxisX, organs.rectumAxisY, 0.0 } }),
      rectumMM }
  };
  if (filling == WallFillingEnum::AlongNormals)
  {
    loads[0].semiAxes = organs.bladderSemiAxes;
    loads[1].center = at({ { organs.rectumAxisX, organs.rectumAxisY, organs.rectumTopZ } });
    loads[1].axis = { { 0, 0, 1 } };
  }
  return loads;
}

} // namespace bmr

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
#include "bmrPhantom.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

namespace bmr {
namespace {

using Vec3 = std::array<double, 3>;

constexpr double Pi = 3.14159265358979323846;

/** \name Pelvis anatomy, in mm relative to the phantom center c (LPS: +x left,
 * +y posterior, +z superior).
 *
 * The numbers were checked numerically for the separations the scene and the
 * mesher rely on: prostate-bladder 4.0 mm, prostate-rectum 4.0 mm,
 * bladder-rectum 5.0 mm, every bone at least 14 mm from every organ and 5.4 mm
 * inside the body outline. Keeping soft tissue between the organs means the
 * label map never has two organs touching, so the mesher produces a soft
 * tissue layer between them and the organs slide independently.
 * \{ */
constexpr double BodySemiAxisX = 85.0;
constexpr double BodySemiAxisY = 65.0;

constexpr Vec3 ProstateCenter{ { 0.0, 5.0, -15.0 } };
constexpr Vec3 ProstateSemiAxes{ { 20.0, 16.0, 18.0 } };

constexpr Vec3 BladderCenter{ { 0.0, -5.0, 30.0 } };
constexpr Vec3 BladderSemiAxes{ { 34.0, 28.0, 24.0 } };

/** The rectum is a vertical cylinder (axis x = 0, y = RectumAxisY) running from
 * below the field of view up to z = RectumTopZ, closed by a hemisphere. */
constexpr double RectumAxisY = 38.0;
constexpr double RectumRadius = 13.0;
constexpr double RectumTopZ = 15.0;

/** The organs of one anatomy: the constants above for the default PelvisAnatomy. */
struct OrganGeometry
{
  Vec3   prostateCenter, prostateSemiAxes;
  Vec3   bladderCenter, bladderSemiAxes;
  double rectumAxisX, rectumAxisY, rectumRadius, rectumTopZ;
};

constexpr Vec3 PubisCenter{ { 0.0, -42.0, -20.0 } };
constexpr Vec3 PubisSemiAxes{ { 20.0, 8.0, 20.0 } };
constexpr Vec3 LeftIliumCenter{ { 58.0, 10.0, 0.0 } };
constexpr Vec3 RightIliumCenter{ { -58.0, 10.0, 0.0 } };
constexpr Vec3 IliumSemiAxes{ { 14.0, 28.0, 45.0 } };
/** \} */

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

/** Refuse grids larger than this: the label and CT buffers alone would need
 * 16 GiB, which is far beyond any phantom the tests or examples need. */
constexpr double MaximumNumberOfVoxels = 2147483648.0;

/** Tissue classes of the pelvis phantom. Seeds are a class of their own so that
 * the boundary test notices them, but they map to the prostate label. */
enum PelvisTissue : std::uint8_t
{
  TissueAir = 0,
  TissueSoft,
  TissueProstate,
  TissueBladder,
  TissueRectum,
  TissueBone,
  TissueSeed,
  NumberOfPelvisTissues
};

constexpr std::array<std::int32_t, NumberOfPelvisTissues> PelvisTissueLabel{
  { PelvisAir, PelvisSoftTissue, PelvisProstate, PelvisBladder, PelvisRectum, PelvisBone, PelvisProstate }
};
constexpr std::array<double, NumberOfPelvisTissues> PelvisTissueHU{
  { -1000.0, 40.0, 45.0, 10.0, -700.0, 700.0, 2500.0 }
};

constexpr std::array<std::int32_t, 3> SphereTissueLabel{ { SphereOutside, SphereOuterShell, SphereInnerCore } };
constexpr std::array<double, 3>       SphereTissueHU{ { -1000.0, 20.0, 60.0 } };

/** splitmix64 (Steele, Lea and Flood 2014). Used instead of the standard
 * distributions because those are implementation-defined: the phantom must be
 * bit-identical on every standard library so that baselines can be shared. */
class SplitMix64
{
public:
  explicit SplitMix64(std::uint64_t seed)
    : m_State(seed)
  {}

  std::uint64_t
  Next()
  {
    m_State += 0x9E3779B97F4A7C15ULL;
    std::uint64_t z = m_State;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

  /** Uniform in [0, 1) with 53 random bits (exactly representable values). */
  double
  Uniform()
  {
    return static_cast<double>(this->Next() >> 11) * (1.0 / 9007199254740992.0);
  }

private:
  std::uint64_t m_State;
};

Vec3
Add(const Vec3 & a, const Vec3 & b)
{
  return { { a[0] + b[0], a[1] + b[1], a[2] + b[2] } };
}

Vec3
Subtract(const Vec3 & a, const Vec3 & b)
{
  return { { a[0] - b[0], a[1] - b[1], a[2] - b[2] } };
}

Vec3
Scale(const Vec3 & a, double s)
{
  return { { a[0] * s, a[1] * s, a[2] * s } };
}

double
Dot(const Vec3 & a, const Vec3 & b)
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/** Axis-aligned ellipsoid with a precomputed bounding box, so that most points
 * are rejected with a few comparisons before any multiplication. */
class Ellipsoid
{
public:
  Ellipsoid(const Vec3 & center, const Vec3 & semiAxes)
    : m_Center(center)
  {
    for (unsigned int a = 0; a < 3; ++a)
    {
      m_InverseSemiAxis[a] = 1.0 / semiAxes[a];
      m_Lower[a] = center[a] - semiAxes[a];
      m_Upper[a] = center[a] + semiAxes[a];
    }
  }

  /** Norm-like level function: < 1 inside, 1 on the surface. It is convex and
   * Lipschitz with constant 1/min(semi-axes), which gives cheap distance bounds. */
  double
  Level(const Vec3 & p) const
  {
    double sum = 0.0;
    for (unsigned int a = 0; a < 3; ++a)
    {
      const double t = (p[a] - m_Center[a]) * m_InverseSemiAxis[a];
      sum += t * t;
    }
    return std::sqrt(sum);
  }

  bool
  Contains(const Vec3 & p) const
  {
    if (p[0] < m_Lower[0] || p[0] > m_Upper[0] || p[1] < m_Lower[1] || p[1] > m_Upper[1] || p[2] < m_Lower[2] ||
        p[2] > m_Upper[2])
    {
      return false;
    }
    double sum = 0.0;
    for (unsigned int a = 0; a < 3; ++a)
    {
      const double t = (p[a] - m_Center[a]) * m_InverseSemiAxis[a];
      sum += t * t;
    }
    return sum <= 1.0;
  }

private:
  Vec3 m_Center;
  Vec3 m_InverseSemiAxis{};
  Vec3 m_Lower{};
  Vec3 m_Upper{};
};

/** Seed cylinder stored relative to the phantom center, with the squared
 * bounding radius used as a cheap rejection test. */
struct SeedCylinder
{
  Vec3   center;
  Vec3   axis;
  double halfLength;
  double radiusSquared;
  double boundingRadiusSquared;

  bool
  Contains(const Vec3 & q) const
  {
    const Vec3   d = Subtract(q, center);
    const double d2 = Dot(d, d);
    if (d2 > boundingRadiusSquared)
    {
      return false;
    }
    const double t = Dot(d, axis);
    return std::abs(t) <= halfLength && d2 - t * t <= radiusSquared;
  }
};

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
    bool farEnough = true;
    for (std::size_t s = 0; s < centers.size() && farEnough; ++s)
    {
      const Vec3 d = Subtract(center, centers[s]);
      farEnough = std::sqrt(Dot(d, d)) >= SeedMinCenterDistance &&
                  SegmentDistance(end0, end1, axes[s].first, axes[s].second) >= SeedMinAxisDistance;
    }
    if (!farEnough)
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

/** Point classifier of the pelvis phantom. Organs are tested in order of their
 * cheapest rejection; they do not overlap, so the order does not change the
 * result. */
class PelvisModel
{
public:
  PelvisModel(const Vec3 & center, const OrganGeometry & organs, const std::vector<Seed> & seeds)
    : m_Center(center)
    , m_Organs(organs)
    , m_Prostate(organs.prostateCenter, organs.prostateSemiAxes)
    , m_Bladder(organs.bladderCenter, organs.bladderSemiAxes)
    , m_Pubis(PubisCenter, PubisSemiAxes)
    , m_LeftIlium(LeftIliumCenter, IliumSemiAxes)
    , m_RightIlium(RightIliumCenter, IliumSemiAxes)
  {
    for (const Seed & seed : seeds)
    {
      SeedCylinder cylinder;
      cylinder.center = Subtract(seed.center, center);
      cylinder.axis = seed.axis;
      cylinder.halfLength = 0.5 * seed.length;
      const double radius = 0.5 * seed.diameter;
      cylinder.radiusSquared = radius * radius;
      cylinder.boundingRadiusSquared = cylinder.halfLength * cylinder.halfLength + cylinder.radiusSquared;
      m_Seeds.push_back(cylinder);
    }
  }

  std::uint8_t
  Classify(const Vec3 & p) const
  {
    const Vec3   q = Subtract(p, m_Center);
    const double bx = q[0] * (1.0 / BodySemiAxisX);
    const double by = q[1] * (1.0 / BodySemiAxisY);
    if (bx * bx + by * by > 1.0)
    {
      return TissueAir;
    }
    if (m_Prostate.Contains(q))
    {
      for (const SeedCylinder & seed : m_Seeds)
      {
        if (seed.Contains(q))
        {
          return TissueSeed;
        }
      }
      return TissueProstate;
    }
    if (m_Bladder.Contains(q))
    {
      return TissueBladder;
    }
    if (InRectum(q))
    {
      return TissueRectum;
    }
    if (m_Pubis.Contains(q) || m_LeftIlium.Contains(q) || m_RightIlium.Contains(q))
    {
      return TissueBone;
    }
    return TissueSoft;
  }

  static std::int32_t
  Label(std::uint8_t tissue)
  {
    return PelvisTissueLabel[tissue];
  }

  static double
  HU(std::uint8_t tissue)
  {
    return PelvisTissueHU[tissue];
  }

private:
  bool
  InRectum(const Vec3 & q) const
  {
    const double dx = q[0] - m_Organs.rectumAxisX;
    const double dy = q[1] - m_Organs.rectumAxisY;
    const double radius = m_Organs.rectumRadius;
    if (std::abs(dx) > radius || std::abs(dy) > radius || q[2] > m_Organs.rectumTopZ + radius)
    {
      return false;
    }
    double r2 = dx * dx + dy * dy;
    if (q[2] > m_Organs.rectumTopZ)
    {
      const double dz = q[2] - m_Organs.rectumTopZ;
      r2 += dz * dz;
    }
    return r2 <= radius * radius;
  }

  Vec3                      m_Center;
  OrganGeometry             m_Organs;
  Ellipsoid                 m_Prostate;
  Ellipsoid                 m_Bladder;
  Ellipsoid                 m_Pubis;
  Ellipsoid                 m_LeftIlium;
  Ellipsoid                 m_RightIlium;
  std::vector<SeedCylinder> m_Seeds;
};

/** Point classifier of the concentric spheres. */
class SphereModel
{
public:
  SphereModel(const Vec3 & center, double innerRadius, double outerRadius)
    : m_Center(center)
    , m_InnerRadiusSquared(innerRadius * innerRadius)
    , m_OuterRadiusSquared(outerRadius * outerRadius)
  {}

  std::uint8_t
  Classify(const Vec3 & p) const
  {
    const Vec3   d = Subtract(p, m_Center);
    const double r2 = Dot(d, d);
    return r2 <= m_InnerRadiusSquared ? 2 : (r2 <= m_OuterRadiusSquared ? 1 : 0);
  }

  static std::int32_t
  Label(std::uint8_t tissue)
  {
    return SphereTissueLabel[tissue];
  }

  static double
  HU(std::uint8_t tissue)
  {
    return SphereTissueHU[tissue];
  }

private:
  Vec3   m_Center;
  double m_InnerRadiusSquared;
  double m_OuterRadiusSquared;
};

/** Inclusive voxel index box. */
struct IndexBox
{
  std::array<long long, 3> lower;
  std::array<long long, 3> upper;
};

/** Voxel boxes that must be supersampled whatever their corners say. A seed is
 * thinner than many voxels, so it can cross a voxel without touching any of its
 * corners or its center; the corner test alone would then drop it. */
std::vector<IndexBox>
SeedIndexBoxes(const GridGeometry & grid, const std::vector<Seed> & seeds)
{
  std::vector<IndexBox> boxes;
  for (const Seed & seed : seeds)
  {
    // Physical bounding box of the capsule around the seed axis (contains the cylinder).
    const double radius = 0.5 * seed.diameter;
    const Vec3   end0 = Subtract(seed.center, Scale(seed.axis, 0.5 * seed.length));
    const Vec3   end1 = Add(seed.center, Scale(seed.axis, 0.5 * seed.length));
    Vec3         lowerPoint{};
    Vec3         upperPoint{};
    for (unsigned int a = 0; a < 3; ++a)
    {
      lowerPoint[a] = std::min(end0[a], end1[a]) - radius;
      upperPoint[a] = std::max(end0[a], end1[a]) + radius;
    }
    Vec3 lowerIndex{
      { std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), std::numeric_limits<double>::max() }
    };
    Vec3 upperIndex{ { std::numeric_limits<double>::lowest(),
                       std::numeric_limits<double>::lowest(),
                       std::numeric_limits<double>::lowest() } };
    for (unsigned int corner = 0; corner < 8; ++corner)
    {
      const Vec3 point{ { (corner & 1) ? upperPoint[0] : lowerPoint[0],
                          (corner & 2) ? upperPoint[1] : lowerPoint[1],
                          (corner & 4) ? upperPoint[2] : lowerPoint[2] } };
      const Vec3 index = grid.PointToIndex(point);
      for (unsigned int a = 0; a < 3; ++a)
      {
        lowerIndex[a] = std::min(lowerIndex[a], index[a]);
        upperIndex[a] = std::max(upperIndex[a], index[a]);
      }
    }
    IndexBox box{};
    bool     empty = false;
    for (unsigned int a = 0; a < 3; ++a)
    {
      // One voxel of margin: a voxel reaches half a voxel beyond its center index.
      const double last = static_cast<double>(grid.size[a]) - 1.0;
      const double lower = std::max(0.0, std::floor(lowerIndex[a]) - 1.0);
      const double upper = std::min(last, std::ceil(upperIndex[a]) + 1.0);
      empty = empty || lower > upper;
      box.lower[a] = static_cast<long long>(lower);
      box.upper[a] = static_cast<long long>(upper);
    }
    if (!empty)
    {
      boxes.push_back(box);
    }
  }
  return boxes;
}

/** Fills the label map (class at the voxel center) and the CT (class HU
 * averaged over 3x3x3 sub-voxel centers).
 *
 * Supersampling every voxel would cost 27 classifications per voxel, so it is
 * done only where the voxel is not homogeneous: the classes at the 8 voxel
 * corners are computed once on the (n+1)^3 corner lattice, two z layers at a
 * time, and a voxel whose corners and center share one class takes that class's
 * HU directly. Convex organs much larger than a voxel cannot hide inside a
 * voxel without reaching a corner; the thin seeds can, hence \a forcedBoxes. */
template<typename TModel>
void
Rasterize(const GridGeometry &          grid,
          const TModel &                model,
          const std::vector<IndexBox> & forcedBoxes,
          std::vector<std::int32_t> &   labels,
          std::vector<float> &          ct)
{
  const std::size_t n0 = grid.size[0];
  const std::size_t n1 = grid.size[1];
  const std::size_t n2 = grid.size[2];
  labels.assign(grid.GetNumberOfVoxels(), 0);
  ct.assign(grid.GetNumberOfVoxels(), 0.0f);

  // Columns of D diag(spacing): the physical step for one index step along each axis.
  std::array<Vec3, 3> step{};
  for (unsigned int c = 0; c < 3; ++c)
  {
    for (unsigned int r = 0; r < 3; ++r)
    {
      step[c][r] = grid.direction[3 * r + c] * grid.spacing[c];
    }
  }
  const auto pointAt = [&grid, &step](double i, double j, double k) -> Vec3 {
    Vec3 p{};
    for (unsigned int r = 0; r < 3; ++r)
    {
      p[r] = grid.origin[r] + step[0][r] * i + step[1][r] * j + step[2][r] * k;
    }
    return p;
  };

  const std::size_t         cornerRow = n0 + 1;
  std::vector<std::uint8_t> lowerLayer(cornerRow * (n1 + 1));
  std::vector<std::uint8_t> upperLayer(cornerRow * (n1 + 1));
  const auto                fillLayer = [&](std::vector<std::uint8_t> & layer, double k) {
    for (std::size_t j = 0; j <= n1; ++j)
    {
      for (std::size_t i = 0; i <= n0; ++i)
      {
        layer[j * cornerRow + i] =
          model.Classify(pointAt(static_cast<double>(i) - 0.5, static_cast<double>(j) - 0.5, k));
      }
    }
  };

  constexpr double              subOffset[3] = { -1.0 / 3.0, 0.0, 1.0 / 3.0 };
  std::vector<const IndexBox *> sliceBoxes;
  std::vector<const IndexBox *> rowBoxes;

  fillLayer(lowerLayer, -0.5);
  for (std::size_t k = 0; k < n2; ++k)
  {
    const double kk = static_cast<double>(k);
    fillLayer(upperLayer, kk + 0.5);
    sliceBoxes.clear();
    for (const IndexBox & box : forcedBoxes)
    {
      if (static_cast<long long>(k) >= box.lower[2] && static_cast<long long>(k) <= box.upper[2])
      {
        sliceBoxes.push_back(&box);
      }
    }
    for (std::size_t j = 0; j < n1; ++j)
    {
      const double jj = static_cast<double>(j);
      rowBoxes.clear();
      for (const IndexBox * box : sliceBoxes)
      {
        if (static_cast<long long>(j) >= box->lower[1] && static_cast<long long>(j) <= box->upper[1])
        {
          rowBoxes.push_back(box);
        }
      }
      const std::uint8_t * lowerRow0 = &lowerLayer[j * cornerRow];
      const std::uint8_t * lowerRow1 = &lowerLayer[(j + 1) * cornerRow];
      const std::uint8_t * upperRow0 = &upperLayer[j * cornerRow];
      const std::uint8_t * upperRow1 = &upperLayer[(j + 1) * cornerRow];
      const std::size_t    offset = n0 * (j + n1 * k);
      for (std::size_t i = 0; i < n0; ++i)
      {
        const double       ii = static_cast<double>(i);
        const std::uint8_t tissue = model.Classify(pointAt(ii, jj, kk));
        labels[offset + i] = TModel::Label(tissue);

        bool homogeneous = lowerRow0[i] == tissue && lowerRow0[i + 1] == tissue && lowerRow1[i] == tissue &&
                           lowerRow1[i + 1] == tissue && upperRow0[i] == tissue && upperRow0[i + 1] == tissue &&
                           upperRow1[i] == tissue && upperRow1[i + 1] == tissue;
        for (const IndexBox * box : rowBoxes)
        {
          if (homogeneous && static_cast<long long>(i) >= box->lower[0] && static_cast<long long>(i) <= box->upper[0])
          {
            homogeneous = false;
          }
        }
        if (homogeneous)
        {
          ct[offset + i] = static_cast<float>(TModel::HU(tissue));
          continue;
        }
        double sum = 0.0;
        for (double dk : subOffset)
        {
          for (double dj : subOffset)
          {
            for (double di : subOffset)
            {
              sum += TModel::HU(model.Classify(pointAt(ii + di, jj + dj, kk + dk)));
            }
          }
        }
        ct[offset + i] = static_cast<float>(sum / 27.0);
      }
    }
    std::swap(lowerLayer, upperLayer);
  }
}

/** Validates the grid and refuses sizes whose buffers could not reasonably be
 * allocated; \a what names the grid in the error message. */
void
CheckPhantomGrid(const GridGeometry & grid, const char * what, const char * where)
{
  grid.Validate(what);
  const double voxels =
    static_cast<double>(grid.size[0]) * static_cast<double>(grid.size[1]) * static_cast<double>(grid.size[2]);
  if (voxels > MaximumNumberOfVoxels)
  {
    std::ostringstream os;
    os << what << ": size " << grid.size[0] << " x " << grid.size[1] << " x " << grid.size[2]
       << " exceeds the maximum of 2^31 voxels";
    Fail(where, os.str());
  }
}

/** Grid of \a size voxels of \a spacing, identity direction, centered on (0,0,0). */
GridGeometry
AxisAlignedCenteredGrid(const std::array<std::size_t, 3> & size, const Vec3 & spacing)
{
  GridGeometry grid;
  grid.size = size;
  grid.spacing = spacing;
  for (unsigned int a = 0; a < 3; ++a)
  {
    grid.origin[a] = -0.5 * (static_cast<double>(size[a]) - 1.0) * spacing[a];
  }
  return grid;
}

Vec3
PhantomCenter(const GridGeometry & grid, bool useGridCenter, const Vec3 & center, const char * where)
{
  if (useGridCenter)
  {
    return GridCenter(grid);
  }
  if (!std::isfinite(center[0]) || !std::isfinite(center[1]) || !std::isfinite(center[2]))
  {
    Fail(where, "the phantom center is not finite");
  }
  return center;
}

} // namespace

PelvisPhantomParameters::PelvisPhantomParameters()
  : grid(AxisAlignedCenteredGrid({ { 160, 128, 64 } }, { { 1.25, 1.25, 2.5 } }))
{}

SpherePhantomParameters::SpherePhantomParameters()
  : grid(AxisAlignedCenteredGrid({ { 96, 96, 96 } }, { { 1.0, 1.0, 1.0 } }))
{}

std::array<double, 3>
GridCenter(const GridGeometry & grid)
{
  const Vec3 centerIndex{ { 0.5 * (static_cast<double>(grid.size[0]) - 1.0),
                            0.5 * (static_cast<double>(grid.size[1]) - 1.0),
                            0.5 * (static_cast<double>(grid.size[2]) - 1.0) } };
  return grid.IndexToPoint(centerIndex);
}

PhantomVolume
MakePelvisPhantom(const PelvisPhantomParameters & parameters)
{
  const char * where = "MakePelvisPhantom";
  CheckPhantomGrid(parameters.grid, "pelvis phantom grid", where);
  if (!(parameters.noiseSigmaHU >= 0.0) || !std::isfinite(parameters.noiseSigmaHU))
  {
    std::ostringstream os;
    os << "noiseSigmaHU = " << parameters.noiseSigmaHU << " must be non-negative and finite";
    Fail(where, os.str());
  }
  const Vec3 center = PhantomCenter(parameters.grid, parameters.useGridCenter, parameters.center, where);

  PhantomVolume volume;
  volume.grid = parameters.grid;
  const OrganGeometry organs = Organs(parameters.anatomy);
  volume.seeds = PlaceSeeds(center, organs, parameters.numberOfSeeds, parameters.seedPlacementSeed);

  const PelvisModel model(center, organs, volume.seeds);
  Rasterize(volume.grid, model, SeedIndexBoxes(volume.grid, volume.seeds), volume.labels, volume.ct);

  if (parameters.noiseSigmaHU > 0.0)
  {
    AddGaussianNoise(volume.ct, parameters.noiseSigmaHU, parameters.noiseSeed);
  }
  return volume;
}

namespace {
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

PhantomVolume
MakeSpherePhantom(const SpherePhantomParameters & parameters)
{
  const char * where = "MakeSpherePhantom";
  CheckPhantomGrid(parameters.grid, "sphere phantom grid", where);
  if (!std::isfinite(parameters.innerRadius) || !std::isfinite(parameters.outerRadius) ||
      !(parameters.innerRadius > 0.0) || !(parameters.outerRadius > parameters.innerRadius))
  {
    std::ostringstream os;
    os << "the radii must satisfy 0 < innerRadius < outerRadius (got " << parameters.innerRadius << " and "
       << parameters.outerRadius << ")";
    Fail(where, os.str());
  }
  const Vec3 center = PhantomCenter(parameters.grid, parameters.useGridCenter, parameters.center, where);

  PhantomVolume volume;
  volume.grid = parameters.grid;
  const SphereModel model(center, parameters.innerRadius, parameters.outerRadius);
  Rasterize(volume.grid, model, std::vector<IndexBox>(), volume.labels, volume.ct);
  return volume;
}

void
AddGaussianNoise(std::vector<float> & values, double sigma, std::uint64_t seed)
{
  if (!(sigma >= 0.0) || !std::isfinite(sigma))
  {
    std::ostringstream os;
    os << "sigma = " << sigma << " must be non-negative and finite";
    Fail("AddGaussianNoise", os.str());
  }
  if (sigma == 0.0)
  {
    return;
  }
  // Box-Muller: each pair of uniforms gives two independent normals, both used.
  SplitMix64        rng(seed);
  const std::size_t n = values.size();
  for (std::size_t i = 0; i < n; i += 2)
  {
    const double u1 = 1.0 - rng.Uniform(); // (0, 1]: the logarithm stays finite
    const double u2 = rng.Uniform();
    const double radius = sigma * std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * Pi * u2;
    values[i] = static_cast<float>(values[i] + radius * std::cos(angle));
    if (i + 1 < n)
    {
      values[i + 1] = static_cast<float>(values[i + 1] + radius * std::sin(angle));
    }
  }
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

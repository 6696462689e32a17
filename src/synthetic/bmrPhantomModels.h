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
// The phantoms' geometry shared by their rasterization and their label functions (private to src/synthetic).
#ifndef bmrPhantomModels_h
#define bmrPhantomModels_h

#include "bmrPhantom.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace bmr {
namespace phantom {

using Vec3 = std::array<double, 3>;

inline constexpr double Pi = 3.14159265358979323846;

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
inline constexpr double BodySemiAxisX = 85.0;
inline constexpr double BodySemiAxisY = 65.0;

inline constexpr Vec3 ProstateCenter{ { 0.0, 5.0, -15.0 } };
inline constexpr Vec3 ProstateSemiAxes{ { 20.0, 16.0, 18.0 } };

inline constexpr Vec3 BladderCenter{ { 0.0, -5.0, 30.0 } };
inline constexpr Vec3 BladderSemiAxes{ { 34.0, 28.0, 24.0 } };

/** The rectum is a vertical cylinder (axis x = 0, y = RectumAxisY) running from
 * below the field of view up to z = RectumTopZ, closed by a hemisphere. */
inline constexpr double RectumAxisY = 38.0;
inline constexpr double RectumRadius = 13.0;
inline constexpr double RectumTopZ = 15.0;

/** The organs of one anatomy: the constants above for the default PelvisAnatomy. */
struct OrganGeometry
{
  Vec3   prostateCenter, prostateSemiAxes;
  Vec3   bladderCenter, bladderSemiAxes;
  double rectumAxisX, rectumAxisY, rectumRadius, rectumTopZ;
};

inline constexpr Vec3 PubisCenter{ { 0.0, -42.0, -20.0 } };
inline constexpr Vec3 PubisSemiAxes{ { 20.0, 8.0, 20.0 } };
inline constexpr Vec3 LeftIliumCenter{ { 58.0, 10.0, 0.0 } };
inline constexpr Vec3 RightIliumCenter{ { -58.0, 10.0, 0.0 } };
inline constexpr Vec3 IliumSemiAxes{ { 14.0, 28.0, 45.0 } };
/** \} */

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

inline constexpr std::array<std::int32_t, NumberOfPelvisTissues> PelvisTissueLabel{
  { PelvisAir, PelvisSoftTissue, PelvisProstate, PelvisBladder, PelvisRectum, PelvisBone, PelvisProstate }
};
inline constexpr std::array<double, NumberOfPelvisTissues> PelvisTissueHU{
  { -1000.0, 40.0, 45.0, 10.0, -700.0, 700.0, 2500.0 }
};

inline constexpr std::array<std::int32_t, 3> SphereTissueLabel{ { SphereOutside, SphereOuterShell, SphereInnerCore } };
inline constexpr std::array<double, 3>       SphereTissueHU{ { -1000.0, 20.0, 60.0 } };

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

inline Vec3
Add(const Vec3 & a, const Vec3 & b)
{
  return { { a[0] + b[0], a[1] + b[1], a[2] + b[2] } };
}

inline Vec3
Subtract(const Vec3 & a, const Vec3 & b)
{
  return { { a[0] - b[0], a[1] - b[1], a[2] - b[2] } };
}

inline Vec3
Scale(const Vec3 & a, double s)
{
  return { { a[0] * s, a[1] * s, a[2] * s } };
}

inline double
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

/** The organs of \a anatomy (see bmrPhantomAnatomy.cxx). */
OrganGeometry
Organs(const PelvisAnatomy & anatomy);

/** Seeds placed by rejection sampling inside the prostate of \a organs, \a phantomCenter added to their centres;
 * fails when \a numberOfSeeds cannot be placed. */
std::vector<Seed>
PlaceSeeds(const Vec3 &          phantomCenter,
           const OrganGeometry & organs,
           unsigned int          numberOfSeeds,
           std::uint64_t         randomSeed);

/** Validates the grid and refuses sizes whose buffers could not reasonably be
 * allocated; \a what names the grid in the error message. */
void
CheckPhantomGrid(const GridGeometry & grid, const char * what, const char * where);

/** Grid of \a size voxels of \a spacing, identity direction, centered on (0,0,0). */
GridGeometry
AxisAlignedCenteredGrid(const std::array<std::size_t, 3> & size, const Vec3 & spacing);

/** The grid's centre when \a useGridCenter, else \a center, which must be finite. */
Vec3
PhantomCenter(const GridGeometry & grid, bool useGridCenter, const Vec3 & center, const char * where);

} // namespace phantom
} // namespace bmr

#endif

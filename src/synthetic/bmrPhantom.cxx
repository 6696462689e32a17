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
// The phantom volumes: the label maps and CTs of the pelvis and sphere phantoms, and the CT noise.
#include "bmrPhantom.h"

#include "bmrError.h"
#include "bmrPhantomModels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

namespace bmr {
namespace phantom {

/** Refuse grids larger than this: the label and CT buffers alone would need
 * 16 GiB, which is far beyond any phantom the tests or examples need. */
constexpr double MaximumNumberOfVoxels = 2147483648.0;

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
    FailInput(where, os.str());
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
    FailInput(where, "the phantom center is not finite");
  }
  return center;
}

} // namespace phantom

namespace {
using phantom::Add;
using phantom::AxisAlignedCenteredGrid;
using phantom::CheckPhantomGrid;
using phantom::OrganGeometry;
using phantom::Organs;
using phantom::PelvisModel;
using phantom::PhantomCenter;
using phantom::Pi;
using phantom::PlaceSeeds;
using phantom::Scale;
using phantom::SphereModel;
using phantom::SplitMix64;
using phantom::Subtract;
using phantom::Vec3;

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

/** Physical points of continuous indices of a grid, as GridGeometry::IndexToPoint with the columns of
 * D diag(spacing) computed once. */
class IndexToPhysical
{
public:
  explicit IndexToPhysical(const GridGeometry & grid)
    : m_Origin(grid.origin)
  {
    // Columns of D diag(spacing): the physical step for one index step along each axis.
    for (unsigned int c = 0; c < 3; ++c)
    {
      for (unsigned int r = 0; r < 3; ++r)
      {
        m_Step[c][r] = grid.direction[3 * r + c] * grid.spacing[c];
      }
    }
  }

  Vec3
  operator()(double i, double j, double k) const
  {
    Vec3 p{};
    for (unsigned int r = 0; r < 3; ++r)
    {
      p[r] = m_Origin[r] + m_Step[0][r] * i + m_Step[1][r] * j + m_Step[2][r] * k;
    }
    return p;
  }

private:
  Vec3                m_Origin;
  std::array<Vec3, 3> m_Step{};
};

/** The classes at the voxel corners of index plane k - 0.5 ... k + 0.5 of an n0 x n1 grid: (n0 + 1) x (n1 + 1) of them
 * at (i - 0.5, j - 0.5, k), row by row. */
template<typename TModel>
void
FillCornerLayer(const TModel &              model,
                const IndexToPhysical &     pointAt,
                std::size_t                 n0,
                std::size_t                 n1,
                double                      k,
                std::vector<std::uint8_t> & layer)
{
  const std::size_t cornerRow = n0 + 1;
  for (std::size_t j = 0; j <= n1; ++j)
  {
    for (std::size_t i = 0; i <= n0; ++i)
    {
      layer[j * cornerRow + i] = model.Classify(pointAt(static_cast<double>(i) - 0.5, static_cast<double>(j) - 0.5, k));
    }
  }
}

/** The classes at the 8 corners of the voxels of one row: rows j and j + 1 of the corner layers below and above. */
struct CornerRows
{
  const std::uint8_t * lower0;
  const std::uint8_t * lower1;
  const std::uint8_t * upper0;
  const std::uint8_t * upper1;

  /** Whether the 8 corners of voxel i are all of class \a tissue. */
  bool
  AllOf(std::size_t i, std::uint8_t tissue) const
  {
    return lower0[i] == tissue && lower0[i + 1] == tissue && lower1[i] == tissue && lower1[i + 1] == tissue &&
           upper0[i] == tissue && upper0[i + 1] == tissue && upper1[i] == tissue && upper1[i + 1] == tissue;
  }
};

/** The class HU of voxel (ii, jj, kk) averaged over its 3x3x3 sub-voxel centres. */
template<typename TModel>
double
SupersampledHU(const TModel & model, const IndexToPhysical & pointAt, double ii, double jj, double kk)
{
  constexpr double subOffset[3] = { -1.0 / 3.0, 0.0, 1.0 / 3.0 };
  double           sum = 0.0;
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
  return sum / 27.0;
}

/** Labels and CT of the n0 voxels of row (jj, kk), written from \a labels and \a ct on; \a rowBoxes: the forced
 * boxes that hold the row. */
template<typename TModel>
void
RasterizeRow(const TModel &                        model,
             const IndexToPhysical &               pointAt,
             const CornerRows &                    corners,
             const std::vector<const IndexBox *> & rowBoxes,
             std::size_t                           n0,
             double                                jj,
             double                                kk,
             std::int32_t *                        labels,
             float *                               ct)
{
  for (std::size_t i = 0; i < n0; ++i)
  {
    const double       ii = static_cast<double>(i);
    const std::uint8_t tissue = model.Classify(pointAt(ii, jj, kk));
    labels[i] = TModel::Label(tissue);

    bool homogeneous = corners.AllOf(i, tissue);
    for (const IndexBox * box : rowBoxes)
    {
      if (homogeneous && static_cast<long long>(i) >= box->lower[0] && static_cast<long long>(i) <= box->upper[0])
      {
        homogeneous = false;
      }
    }
    if (homogeneous)
    {
      ct[i] = static_cast<float>(TModel::HU(tissue));
      continue;
    }
    ct[i] = static_cast<float>(SupersampledHU(model, pointAt, ii, jj, kk));
  }
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

  const IndexToPhysical pointAt(grid);

  const std::size_t             cornerRow = n0 + 1;
  std::vector<std::uint8_t>     lowerLayer(cornerRow * (n1 + 1));
  std::vector<std::uint8_t>     upperLayer(cornerRow * (n1 + 1));
  std::vector<const IndexBox *> sliceBoxes;
  std::vector<const IndexBox *> rowBoxes;

  FillCornerLayer(model, pointAt, n0, n1, -0.5, lowerLayer);
  for (std::size_t k = 0; k < n2; ++k)
  {
    const double kk = static_cast<double>(k);
    FillCornerLayer(model, pointAt, n0, n1, kk + 0.5, upperLayer);
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
      const CornerRows  corners{ &lowerLayer[j * cornerRow],
                                &lowerLayer[(j + 1) * cornerRow],
                                &upperLayer[j * cornerRow],
                                &upperLayer[(j + 1) * cornerRow] };
      const std::size_t offset = n0 * (j + n1 * k);
      RasterizeRow(model, pointAt, corners, rowBoxes, n0, jj, kk, &labels[offset], &ct[offset]);
    }
    std::swap(lowerLayer, upperLayer);
  }
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
    FailInput(where, os.str());
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
    FailInput(where, os.str());
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
    FailInput("AddGaussianNoise", os.str());
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

} // namespace bmr

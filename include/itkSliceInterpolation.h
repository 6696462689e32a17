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
#ifndef itkSliceInterpolation_h
#define itkSliceInterpolation_h

#include "itkImage.h"
#include "itkSignedMaurerDistanceMapImageFilter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

namespace itk {

/** Thick slices: the largest voxel side is at least this many times each of the two others. Clinical planning CTs
 * (0.9-1.2 mm in-plane, 2-3 mm slices) have them; the 1 mm phantoms and mildly anisotropic grids do not. */
constexpr double SliceInterpolationMinimumRatio = 1.5;

/** The slice axis of a grid with thick slices and how many fine slices each slice step is cut into. */
struct SliceInterpolationGeometry
{
  int          axis{ -1 };  ///< image axis of the thick slices; -1: the slices are not thick
  unsigned int factor{ 1 }; ///< m = round(slice spacing / finest in-plane spacing)
};

/** The thick-slice axis of \a image (SliceInterpolationMinimumRatio), or axis -1 when it has none. */
template<typename TImage>
SliceInterpolationGeometry
ThickSlices(const TImage * image)
{
  const auto & spacing = image->GetSpacing();
  unsigned int thick = 0;
  for (unsigned int a = 1; a < 3; ++a)
  {
    thick = spacing[a] > spacing[thick] ? a : thick;
  }
  double finest = NumericTraits<double>::max(), coarsest = 0.0; // in-plane
  for (unsigned int a = 0; a < 3; ++a)
  {
    finest = a == thick ? finest : std::min(finest, double(spacing[a]));
    coarsest = a == thick ? coarsest : std::max(coarsest, double(spacing[a]));
  }
  SliceInterpolationGeometry g;
  if (spacing[thick] >= SliceInterpolationMinimumRatio * coarsest &&
      image->GetLargestPossibleRegion().GetSize(thick) >= 2)
  {
    g.axis = static_cast<int>(thick);
    g.factor = static_cast<unsigned int>(std::lround(spacing[thick] / finest));
  }
  return g;
}

namespace detail {
/** The in-plane signed distance [mm, negative inside] of one slice's mask (\a nx x \a ny, x fastest) to the faces of
 * its pixels: Maurer's map of the mask and of its complement, averaged, as MaskAndComplementMap() in 3-D. The mask
 * must hold both values. */
inline std::vector<float>
SliceFaceDistance(const std::vector<unsigned char> & mask, std::size_t nx, std::size_t ny, double sx, double sy)
{
  using MaskType = Image<unsigned char, 2>;
  using MapType = Image<float, 2>;
  std::vector<float> phi(mask.size(), 0.0f);
  for (int complement = 0; complement < 2; ++complement)
  {
    auto               image = MaskType::New();
    MaskType::SizeType size = { { nx, ny } };
    image->SetRegions(size);
    const double spacing[2] = { sx, sy };
    image->SetSpacing(spacing);
    image->Allocate();
    unsigned char * out = image->GetBufferPointer();
    for (std::size_t p = 0; p < mask.size(); ++p)
    {
      out[p] = static_cast<unsigned char>(complement ? !mask[p] : mask[p]);
    }
    auto distance = SignedMaurerDistanceMapImageFilter<MaskType, MapType>::New();
    distance->SetInput(image);
    distance->SetUseImageSpacing(true);
    distance->SetSquaredDistance(false);
    distance->SetInsideIsPositive(false);
    distance->SetBackgroundValue(0);
    distance->Update();
    const float * map = distance->GetOutput()->GetBufferPointer();
    for (std::size_t p = 0; p < mask.size(); ++p)
    {
      phi[p] += complement ? -0.5f * map[p] : 0.5f * map[p];
    }
  }
  return phi;
}

/** One label's in-plane distance on one slice, with what the interpolation needs of a slice it does not cross. */
struct SliceLabelMap
{
  std::vector<float> phi;              ///< in-plane face distance [mm]; empty when the slice has no boundary
  bool               present{ false }; ///< the label occurs in the slice
  float              deepest{ 0.0f };  ///< largest distance inside [mm]
  float              farthest{ 0.0f }; ///< largest distance outside [mm]
};

/** phi_l on one slice: the map, or one value where the label does not cross the slice. */
struct SliceValues
{
  const float * phi;
  float         constant;
  float
  At(std::size_t p) const
  {
    return phi ? phi[p] : constant;
  }
};

/** The slices of a label image along \a axis: pixel p = i_b + n_b i_c of slice s (b < c the in-plane axes), the
 * labels each slice holds, and the in-plane maps of its labels, each computed once and forgotten when passed. */
template<typename TLabelImage>
class SliceStack
{
public:
  using PixelType = typename TLabelImage::PixelType;

  SliceStack(const TLabelImage * labels, unsigned int axis)
    : m_Labels(labels)
    , m_Axis(axis)
    , m_B(axis == 0 ? 1 : 0)
    , m_C(axis == 2 ? 1 : 2)
  {
    for (unsigned int d = 0; d < 3; ++d)
    {
      m_Size[d] = labels->GetLargestPossibleRegion().GetSize(d);
    }
    m_Present.resize(m_Size[m_Axis]);
    for (std::size_t s = 0; s < Slices(); ++s)
    {
      for (std::size_t p = 0; p < Pixels(); ++p)
      {
        m_Present[s].insert(Label(p, s));
      }
    }
  }

  std::size_t
  Slices() const
  {
    return m_Size[m_Axis];
  }
  std::size_t
  Pixels() const
  {
    return m_Size[m_B] * m_Size[m_C];
  }
  /** The buffer offset of pixel p on slice s of a grid of \a size (the input's, or one refined along the axis). */
  std::size_t
  Offset(std::size_t p, std::size_t s, const std::size_t size[3]) const
  {
    const std::size_t stride[3] = { 1, size[0], size[0] * size[1] };
    return (p % m_Size[m_B]) * stride[m_B] + (p / m_Size[m_B]) * stride[m_C] + s * stride[m_Axis];
  }
  PixelType
  Label(std::size_t p, std::size_t s) const
  {
    return m_Labels->GetBufferPointer()[Offset(p, s, m_Size)];
  }
  const std::set<PixelType> &
  Present(std::size_t s) const
  {
    return m_Present[s];
  }

  /** phi_l on slice s: its map, or, where the label does not cross the slice, its neighbours' extreme distance. */
  SliceValues
  Values(std::size_t s, PixelType l)
  {
    const SliceLabelMap & map = Map(s, l);
    if (!map.phi.empty())
    {
      return SliceValues{ map.phi.data(), 0.0f };
    }
    float cap = 0.0f;
    for (std::size_t t : { s - 1, s + 1 })
    {
      if (t < Slices()) // s - 1 wraps around for s = 0
      {
        const SliceLabelMap & neighbour = Map(t, l);
        cap = std::max(cap, neighbour.phi.empty() ? 0.0f : (map.present ? neighbour.farthest : neighbour.deepest));
      }
    }
    constexpr float far = 1e20f;
    cap = cap > 0.0f ? cap : far;
    return SliceValues{ nullptr, map.present ? -cap : cap };
  }

  /** Drops the maps of the slices below \a s - 1, which the intervals from s on do not read. */
  void
  ForgetBelow(std::size_t s)
  {
    for (auto it = m_Maps.begin(); it != m_Maps.end();)
    {
      it = it->first.first + 1 < s ? m_Maps.erase(it) : std::next(it);
    }
  }

private:
  const SliceLabelMap &
  Map(std::size_t s, PixelType l)
  {
    const auto key = std::make_pair(s, l);
    const auto found = m_Maps.find(key);
    if (found != m_Maps.end())
    {
      return found->second;
    }
    SliceLabelMap map;
    map.present = m_Present[s].count(l) > 0;
    if (map.present && m_Present[s].size() > 1)
    {
      std::vector<unsigned char> mask(Pixels());
      for (std::size_t p = 0; p < Pixels(); ++p)
      {
        mask[p] = Label(p, s) == l;
      }
      const auto & spacing = m_Labels->GetSpacing();
      map.phi = SliceFaceDistance(mask, m_Size[m_B], m_Size[m_C], spacing[m_B], spacing[m_C]);
      for (float v : map.phi)
      {
        map.deepest = std::max(map.deepest, -v);
        map.farthest = std::max(map.farthest, v);
      }
    }
    return m_Maps.emplace(key, std::move(map)).first->second;
  }

  const TLabelImage *                                        m_Labels;
  unsigned int                                               m_Axis, m_B, m_C;
  std::size_t                                                m_Size[3];
  std::vector<std::set<PixelType>>                           m_Present;
  std::map<std::pair<std::size_t, PixelType>, SliceLabelMap> m_Maps;
};

/** An image on \a labels' grid refined \a factor times along \a axis, its first slice on the input's first. */
template<typename TLabelImage>
typename TLabelImage::Pointer
RefinedAlongAxis(const TLabelImage * labels, unsigned int axis, std::size_t factor)
{
  const auto                       region = labels->GetLargestPossibleRegion();
  typename TLabelImage::SizeType   size = region.GetSize();
  typename TLabelImage::PointType  origin;
  typename TLabelImage::RegionType fine;
  size[axis] = (size[axis] - 1) * factor + 1;
  fine.SetSize(size);
  labels->TransformIndexToPhysicalPoint(region.GetIndex(), origin);
  auto spacing = labels->GetSpacing();
  spacing[axis] /= double(factor);
  auto out = TLabelImage::New();
  out->SetRegions(fine);
  out->SetOrigin(origin);
  out->SetSpacing(spacing);
  out->SetDirection(labels->GetDirection());
  out->Allocate();
  return out;
}
} // namespace detail

/** \brief Shape-based interpolation of a label map between its thick slices.
 *
 * A label map of a CT with thick slices (2-3 mm against 1 mm in-plane) samples each organ's cross-section on every
 * slice and says nothing between: its voxel faces make a staircase of slice-thick terraces, and two scans of the
 * same anatomy on grids a fraction of a slice apart disagree by up to a slice there. The organ's cross-sections are
 * known far better than that, so between slices they are interpolated, as planning systems interpolate contours
 * (shape-based interpolation, Raya and Udupa 1990; Herman, Zheng and Bucholtz 1992): for every label l the
 * in-plane signed distance \f$ \phi_{l,s}(p) \f$ to the faces of its pixels on slice s (detail::SliceFaceDistance)
 * is interpolated linearly along the slice axis, \f$ \phi_l(p, s + t) = (1 - t)\, \phi_{l,s}(p) + t\, \phi_{l,s+1}(p)
 * \f$, and every voxel of a grid refined m times along that axis takes the label of least \f$ \phi_l \f$. On a slice
 * without the label, \f$ \phi_l \f$ is the deepest distance inside of its neighbouring slices' cross-sections, so an
 * organ's end is a dome that reaches half a slice beyond its last cross-section at its deepest point and ends at
 * the cross-section's rim (the midpoint, on average, of where a convex organ's tip lies between two slices); on a
 * slice the label fills, minus the farthest distance outside of its neighbours'. That dome is a prior for rounded
 * organs: a flat face parallel to the slices (a box's, itkSliceInterpolationTest) is read worse than by the
 * nearest slice.
 *
 * The output grid has the input's origin, direction and in-plane spacing, the slice axis's spacing divided by m =
 * ThickSlices().factor and (n - 1) m + 1 voxels along it: fine slice m s is input slice s, whose labels it keeps
 * exactly. Returns \a labels itself when its slices are not thick (ThickSlices()). Deterministic: every voxel
 * depends on its two slices only. Memory: four slices' maps per label at a time (detail::SliceStack).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationScene */
template<typename TLabelImage>
typename TLabelImage::ConstPointer
InterpolateLabelSlices(const TLabelImage * labels)
{
  using PixelType = typename TLabelImage::PixelType;
  const SliceInterpolationGeometry g = ThickSlices(labels);
  if (g.axis < 0 || g.factor < 2)
  {
    return labels;
  }
  const auto                      axis = static_cast<unsigned int>(g.axis);
  const std::size_t               m = g.factor;
  detail::SliceStack<TLabelImage> stack(labels, axis);
  const auto                      out = detail::RefinedAlongAxis(labels, axis, m);
  const auto &                    outSize = out->GetLargestPossibleRegion().GetSize();
  const std::size_t               fineSize[3] = { outSize[0], outSize[1], outSize[2] };
  PixelType *                     target = out->GetBufferPointer();
  for (std::size_t s = 0; s < stack.Slices(); ++s)
  {
    for (std::size_t p = 0; p < stack.Pixels(); ++p)
    {
      target[stack.Offset(p, s * m, fineSize)] = stack.Label(p, s); // the input's slices stay as they are
    }
    if (s + 1 == stack.Slices())
    {
      break;
    }
    stack.ForgetBelow(s);
    // The fine slices between s and s + 1: the labels of either, each at its least interpolated distance.
    std::set<PixelType> candidates = stack.Present(s);
    candidates.insert(stack.Present(s + 1).begin(), stack.Present(s + 1).end());
    std::vector<std::pair<PixelType, std::array<detail::SliceValues, 2>>> ends;
    for (PixelType l : candidates)
    {
      ends.push_back({ l, { { stack.Values(s, l), stack.Values(s + 1, l) } } });
    }
    for (std::size_t j = 1; j < m; ++j)
    {
      const float t = float(j) / float(m);
      for (std::size_t p = 0; p < stack.Pixels(); ++p)
      {
        float     best = NumericTraits<float>::max();
        PixelType label = stack.Label(p, s);
        for (const auto & [l, end] : ends)
        {
          const float phi = (1.0f - t) * end[0].At(p) + t * end[1].At(p);
          if (phi < best)
          {
            best = phi;
            label = l;
          }
        }
        target[stack.Offset(p, s * m + j, fineSize)] = label;
      }
    }
  }
  return out.GetPointer();
}

} // namespace itk

#endif

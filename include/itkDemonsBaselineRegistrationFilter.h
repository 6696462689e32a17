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
#ifndef itkDemonsBaselineRegistrationFilter_h
#define itkDemonsBaselineRegistrationFilter_h

#include <cstdint>
#include <ostream>
#include "itkImageToImageFilter.h"
#include "itkVector.h"

#include <cstdint>
#include <array>
#include <vector>

namespace itk {

/** \class DemonsBaselineRegistrationFilterEnums
 * \brief The enums of DemonsBaselineRegistrationFilter (ITK 5 style: outside the class template, with operator<<).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
class DemonsBaselineRegistrationFilterEnums
{
public:
  /** Which ITK Demons filter runs at every level. */
  enum class Variant : std::uint8_t
  {
    Diffeomorphic,
    FastSymmetricForces,
  };
};
/** Prints the enumerator's full name. */
inline std::ostream &
operator<<(std::ostream & out, const DemonsBaselineRegistrationFilterEnums::Variant value)
{
  switch (value)
  {
    case DemonsBaselineRegistrationFilterEnums::Variant::Diffeomorphic:
      return out << "itk::DemonsBaselineRegistrationFilterEnums::Variant::Diffeomorphic";
    case DemonsBaselineRegistrationFilterEnums::Variant::FastSymmetricForces:
      return out << "itk::DemonsBaselineRegistrationFilterEnums::Variant::FastSymmetricForces";
  }
  return out << "INVALID VALUE FOR itk::DemonsBaselineRegistrationFilterEnums::Variant";
}

/** \class DemonsBaselineRegistrationFilter
 * \brief Intensity-based baseline for the physics-based registration: ITK's Demons in a multi-resolution
 * pyramid, with histogram matching and optional flattening of organs. A composite of existing ITK
 * filters, not a new Demons.
 *
 * Pipeline:
 * 1. both images are cast to float; optionally, every voxel of a chosen organ is replaced by the organ's
 *    mean intensity in that image (FlattenLabels, with the fixed and moving label maps), so that structure
 *    inside the organ (implanted seeds in the prostate) cannot drive the registration — as in dissertation
 *    §3.3.4, where the comparison is on those seeds;
 * 2. the moving image's histogram is matched to the fixed one (HistogramMatchingImageFilter, HistogramLevels
 *    levels, MatchPoints match points, voxels below the mean excluded), unless HistogramMatching is off;
 * 3. MultiResolutionPDEDeformableRegistration with NumberOfLevels levels (each level halves the resolution),
 *    NumberOfIterations[level] iterations per level from coarse to fine, around either
 *    - DiffeomorphicDemonsRegistrationFilter (Variant Diffeomorphic, the default): s <- s o exp(u), or
 *    - FastSymmetricForcesDemonsRegistrationFilter (Variant FastSymmetricForces): s <- s + u,
 *    both with the symmetric (fixed + warped moving) gradient, update steps limited to
 *    MaximumUpdateStepLength voxels and the displacement smoothed by a Gaussian of StandardDeviation voxels
 *    after every iteration (the elastic-like regularization of Demons).
 *
 * The update of one iteration at voxel x, with f the fixed image, m∘s the warped moving image and
 * J = (∇f + ∇(m∘s)) / 2, is u(x) = (f − m∘s) J / (‖J‖² + (f − m∘s)² / K), K the mean squared voxel size.
 *
 * Output: the displacement field d on the fixed image's grid, fixed → moving in ITK's convention:
 * the fixed point x corresponds to the moving point x + d(x) [mm]. Warp the moving image with ImageWarper.
 *
 * Defaults (documented in the README): 3 levels × 50 iterations, σ = 1.5 voxels, step ≤ 2 voxels,
 * histogram matching with 1024 levels and 7 match points (its run times: docs/history/benchmarks.md, side by side).
 *
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
template<typename TImage,
         typename TDisplacementField = Image<Vector<double, TImage::ImageDimension>, TImage::ImageDimension>,
         typename TLabelImage = Image<std::int32_t, TImage::ImageDimension>>
class ITK_TEMPLATE_EXPORT DemonsBaselineRegistrationFilter : public ImageToImageFilter<TImage, TDisplacementField>
{
public:
  ITK_DISALLOW_COPY_AND_MOVE(DemonsBaselineRegistrationFilter);

  using Self = DemonsBaselineRegistrationFilter;
  using Superclass = ImageToImageFilter<TImage, TDisplacementField>;
  using Pointer = SmartPointer<Self>;
  using ConstPointer = SmartPointer<const Self>;

  static constexpr unsigned int ImageDimension = TImage::ImageDimension;
  using ImageType = TImage;
  using DisplacementFieldType = TDisplacementField;
  using LabelImageType = TLabelImage;
  using LabelType = typename LabelImageType::PixelType;

  itkNewMacro(Self);
  itkTypeMacro(DemonsBaselineRegistrationFilter, ImageToImageFilter);

  using VariantEnum = DemonsBaselineRegistrationFilterEnums::Variant;

  /** The fixed image defines the output grid. */
  void
  SetFixedImage(const ImageType * image);
  const ImageType *
  GetFixedImage() const;
  void
  SetMovingImage(const ImageType * image);
  const ImageType *
  GetMovingImage() const;

  /** Label maps on the grids of the fixed and the moving image; needed only when FlattenLabels is not empty. */
  void
  SetFixedLabelImage(const LabelImageType * labels);
  void
  SetMovingLabelImage(const LabelImageType * labels);

  /** Organs whose intensities are replaced by their mean in each image (empty: none). */
  void
  SetFlattenLabels(const std::vector<LabelType> & labels)
  {
    if (labels != m_FlattenLabels)
    {
      m_FlattenLabels = labels;
      this->Modified();
    }
  }
  const std::vector<LabelType> &
  GetFlattenLabels() const
  {
    return m_FlattenLabels;
  }

  itkSetEnumMacro(Variant, VariantEnum);
  itkGetEnumMacro(Variant, VariantEnum);

  /** Number of pyramid levels (>= 1); the iterations per level are reset to DefaultIterations each. */
  void
  SetNumberOfLevels(unsigned int levels);
  itkGetConstMacro(NumberOfLevels, unsigned int);

  /** Iterations per level, coarse to fine; its length must equal NumberOfLevels. */
  void
  SetNumberOfIterations(const std::vector<unsigned int> & iterations);
  const std::vector<unsigned int> &
  GetNumberOfIterations() const
  {
    return m_NumberOfIterations;
  }

  /** Standard deviation of the Gaussian that smooths the displacement field [voxels]. */
  itkSetMacro(StandardDeviation, double);
  itkGetConstMacro(StandardDeviation, double);
  /** Longest update per iteration [voxels]. */
  itkSetMacro(MaximumUpdateStepLength, double);
  itkGetConstMacro(MaximumUpdateStepLength, double);
  itkSetMacro(HistogramMatching, bool);
  itkGetConstMacro(HistogramMatching, bool);
  itkBooleanMacro(HistogramMatching);
  itkSetMacro(HistogramLevels, unsigned int);
  itkGetConstMacro(HistogramLevels, unsigned int);
  itkSetMacro(MatchPoints, unsigned int);
  itkGetConstMacro(MatchPoints, unsigned int);

  /** Mean squared intensity difference of the last iteration (of the finest level). */
  itkGetConstMacro(FinalMetric, double);

protected:
  DemonsBaselineRegistrationFilter();
  ~DemonsBaselineRegistrationFilter() override = default;

  void
  VerifyPreconditions() ITKv5_CONST override;
  void
  GenerateOutputInformation() override;
  void
  GenerateInputRequestedRegion() override;
  void
  GenerateData() override;
  void
  PrintSelf(std::ostream & os, Indent indent) const override;

private:
  using FloatImageType = Image<float, ImageDimension>;
  /** The fixed and the moving image as float, the flattened labels replaced by their means, the moving one matched
   * to the fixed one's histogram when asked. */
  std::array<typename FloatImageType::Pointer, 2>
  PreparedImages() const;

  VariantEnum               m_Variant{ VariantEnum::Diffeomorphic };
  unsigned int              m_NumberOfLevels{ 3 };
  std::vector<unsigned int> m_NumberOfIterations{ 50, 50, 50 };
  double                    m_StandardDeviation{ 1.5 };
  double                    m_MaximumUpdateStepLength{ 2.0 };
  bool                      m_HistogramMatching{ true };
  unsigned int              m_HistogramLevels{ 1024 };
  unsigned int              m_MatchPoints{ 7 };
  std::vector<LabelType>    m_FlattenLabels;
  double                    m_FinalMetric{ 0.0 };
};

} // namespace itk

#ifndef ITK_MANUAL_INSTANTIATION
#  include "itkDemonsBaselineRegistrationFilter.hxx"
#endif

#endif

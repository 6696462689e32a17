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
#ifndef itkLandmarkRegistrationError_h
#define itkLandmarkRegistrationError_h

#include "bmrLandmarks.h"
#include "itkVectorLinearInterpolateImageFunction.h"

#include <cmath>
#include <map>
#include <vector>

namespace itk {

/** \brief Target registration error [mm] of each landmark pair under a fixed → moving displacement field.
 *
 * In ITK's convention the field d maps the fixed point x to the moving point x + d(x), so for the landmark
 * pair (x_f, x_m) with the same id,
 * \f[ \mathrm{TRE} = \lVert x_f + d(x_f) - x_m \rVert_2 , \f]
 * d trilinearly interpolated at x_f. The identity (d = 0) gives the landmarks' own displacement, the floor
 * every registration should beat. Landmarks are paired by id; the result follows the order of \a fixed.
 * Throws itk::ExceptionObject naming the landmark when an id has no partner or a fixed landmark lies
 * outside the field's grid (between the outermost voxel centers).
 * \ingroup BiomechanicalRegistration BiomechanicalRegistrationEvaluation
 */
template<typename TDisplacementField>
std::vector<double>
ComputeTargetRegistrationErrors(const TDisplacementField *         field,
                                const std::vector<bmr::Landmark> & fixed,
                                const std::vector<bmr::Landmark> & moving)
{
  static_assert(TDisplacementField::ImageDimension == 3, "landmarks are 3-D");
  using InterpolatorType = VectorLinearInterpolateImageFunction<TDisplacementField, double>;
  auto interpolator = InterpolatorType::New();
  interpolator->SetInputImage(field);
  std::map<std::string, const bmr::Landmark *> byId;
  for (const bmr::Landmark & m : moving)
  {
    byId[m.id] = &m;
  }
  std::vector<double> errors;
  for (const bmr::Landmark & f : fixed)
  {
    const auto partner = byId.find(f.id);
    if (partner == byId.end())
    {
      itkGenericExceptionMacro(<< "landmark \"" << f.id << "\" of the fixed image has no moving partner");
    }
    typename InterpolatorType::PointType x;
    for (unsigned int a = 0; a < 3; ++a)
    {
      x[a] = f.point[a];
    }
    if (!interpolator->IsInsideBuffer(x))
    {
      itkGenericExceptionMacro(<< "landmark \"" << f.id << "\" at (" << x[0] << ", " << x[1] << ", " << x[2]
                               << ") mm lies outside the displacement field");
    }
    const auto d = interpolator->Evaluate(x);
    double     e2 = 0.0;
    for (unsigned int a = 0; a < 3; ++a)
    {
      const double r = x[a] + d[a] - partner->second->point[a];
      e2 += r * r;
    }
    errors.push_back(std::sqrt(e2));
  }
  return errors;
}

} // namespace itk

#endif

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
#ifndef bmrSecantSearch_h
#define bmrSecantSearch_h

#include "BiomechanicalRegistrationExport.h"

#include <functional>
#include <string>

namespace bmr {

/** One evaluated point of a one-dimensional search: x, f(x) and f'(x). An inexact point is known only to a looser
 * precision (f from above, f' to about its error); SecantSearch steps from it but refines it before stopping on it. */
struct BiomechanicalRegistration_EXPORT SecantPoint
{
  double x{ 0.0 };
  double value{ 0.0 };
  double derivative{ 0.0 };
  bool   exact{ true };
};

/** Settings of SecantSearch. */
struct BiomechanicalRegistration_EXPORT SecantSearchSettings
{
  double       lowerBound{ 0.0 };
  double       upperBound{ 1.0 };
  double       curvatureGuess{ 0.0 };      ///< f'' expected near the start; <= 0: unknown
  double       maximumStep{ 0.5 };         ///< largest |x_{k+1} - x_k|
  double       stepTolerance{ 1e-3 };      ///< stop when the next step would be shorter
  double       derivativeTolerance{ 0.0 }; ///< stop when |f'| is not larger (absolute)
  unsigned int maximumEvaluations{ 20 };   ///< of evaluate(); refine() comes on top, at most once per point
};

/** What SecantSearch found: the evaluated point of least f, how many evaluations, why it stopped, and
 * whether the minimum lies on a bound (f' pointing out of the interval there). */
struct BiomechanicalRegistration_EXPORT SecantSearchResult
{
  SecantPoint  best;
  unsigned int evaluations{ 0 };
  bool         onBound{ false };
  unsigned int refinements{ 0 }; ///< inexact points evaluated again exactly (not counted in evaluations)
  double       curvature{ 0.0 }; ///< the last secant (or the guess) of f''
  std::string  stopCondition;
};

/** \brief Minimum of a smooth f on [a, b] from its derivative: a safeguarded secant (Newton) iteration on
 * f'(x) = 0.
 *
 * Each step is \f$ x_{k+1} = x_k - f'(x_k)/c_k \f$ with the secant curvature
 * \f$ c_k = (f'(x_k) - f'(x_{k-1}))/(x_k - x_{k-1}) \f$ (the guess before the second evaluation); when c is not
 * positive, a step of maximumStep downhill. Steps are limited to maximumStep and kept inside the bracket the
 * evaluated signs of f' establish (bisection when the secant leaves it) and inside [a, b]. Stops when
 * |f'| <= derivativeTolerance, when the next step would be shorter than stepTolerance, at a bound whose
 * derivative points outwards, or after maximumEvaluations. Where f is a convex parabola and the guess is
 * its curvature, one step lands on the minimum; near a simple minimum convergence is superlinear (order
 * 1.618). Used for the outer search over log E of one unknown modulus, where each evaluation is an inner
 * solve and the sweep supplies the curvature guess: the general bounded L-BFGS needs about two more
 * evaluations for the same tolerance, because it starts with a unit step of unknown scale.
 *
 * \a evaluate may return inexact points (SecantPoint::exact false), cheaper evaluations whose f' is known to less
 * than derivativeTolerance: the search steps from them, and when it would stop on one (any of the conditions
 * above), it asks \a refine for the exact point at the same x and decides again. So the search only stops on an
 * exact point, and the best point is the exact one of least f. Far from the minimum, where |f'| is large, f''s
 * error moves the next step by about error / f''. In the outer search an inexact point is an inner solve to a
 * looser tolerance, and its refinement that solve continued to the full one.
 * Deterministic; holds no state between calls. */
BiomechanicalRegistration_EXPORT SecantSearchResult
SecantSearch(const std::function<SecantPoint(double x)> & evaluate,
             double                                       start,
             const SecantSearchSettings &                 settings,
             const std::function<SecantPoint(double x)> & refine = {});

} // namespace bmr

#endif

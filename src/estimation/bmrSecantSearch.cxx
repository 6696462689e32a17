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
#include "bmrSecantSearch.h"

#include "bmrError.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace bmr {
namespace {
void
CheckSettings(const SecantSearchSettings & s, double start)
{
  if (!(std::isfinite(s.lowerBound) && std::isfinite(s.upperBound) && s.lowerBound < s.upperBound))
  {
    Fail("SecantSearch", "the bounds must be finite with lower < upper");
  }
  if (!(s.maximumStep > 0.0) || !(s.stepTolerance >= 0.0) || !(s.derivativeTolerance >= 0.0) ||
      s.maximumEvaluations < 1 || !std::isfinite(start))
  {
    Fail("SecantSearch", "needs a finite start, a positive maximum step, non-negative tolerances and an evaluation");
  }
}

void
CheckFinite(const SecantPoint & p)
{
  if (!std::isfinite(p.value) || !std::isfinite(p.derivative))
  {
    std::ostringstream msg;
    msg << "the function or its derivative is not finite at x = " << p.x;
    Fail("SecantSearch", msg.str());
  }
}

/** \a p lies lower than \a q, or as low within rounding and with a smaller |f'| (near the minimum, f changes
 * by f'' e^2 / 2, below its own precision, while f' still tells which point is closer). */
bool
Better(const SecantPoint & p, const SecantPoint & q)
{
  const double rounding = 8.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(p.value), std::abs(q.value));
  return p.value < q.value - rounding ||
         (std::abs(p.value - q.value) <= rounding && std::abs(p.derivative) < std::abs(q.derivative));
}

/** The interval [lo, hi] known to hold a stationary point: each end is a bound or a point whose derivative
 * points inwards (f'(lo) < 0, f'(hi) > 0). */
struct Bracket
{
  double lo, hi;
  bool   loSampled{ false }, hiSampled{ false };

  void
  Update(const SecantPoint & p)
  {
    if (p.derivative > 0.0 && p.x < hi)
    {
      hi = p.x;
      hiSampled = true;
    }
    else if (p.derivative < 0.0 && p.x > lo)
    {
      lo = p.x;
      loSampled = true;
    }
  }
  /** \a next kept strictly inside: at the far side's bound when that is unsampled, else bisected. */
  double
  Keep(const SecantPoint & p, double next) const
  {
    if (next > lo && next < hi)
    {
      return next;
    }
    if (p.derivative > 0.0)
    {
      return loSampled ? 0.5 * (lo + std::min(p.x, hi)) : lo;
    }
    return hiSampled ? 0.5 * (hi + std::max(p.x, lo)) : hi;
  }
};

/** The next x from \a p: Newton's step with the secant curvature through \a previous (when given and apart; else
 * \a curvature as it is), or \a maximumStep downhill when that is not positive; limited to \a maximumStep and kept
 * inside \a bracket, which takes \a p first. */
double
SecantStep(const SecantPoint & p,
           const SecantPoint * previous,
           double              maximumStep,
           Bracket &           bracket,
           double &            curvature)
{
  bracket.Update(p);
  if (previous != nullptr && p.x != previous->x)
  {
    curvature = (p.derivative - previous->derivative) / (p.x - previous->x);
  }
  double step = curvature > 0.0 ? -p.derivative / curvature : std::copysign(maximumStep, -p.derivative);
  step = std::clamp(step, -maximumStep, maximumStep);
  return bracket.Keep(p, p.x + step);
}
} // namespace

SecantSearchResult
SecantSearch(const std::function<SecantPoint(double x)> & evaluate,
             double                                       start,
             const SecantSearchSettings &                 s,
             const std::function<SecantPoint(double x)> & refine)
{
  CheckSettings(s, start);
  SecantSearchResult r;
  Bracket            bracket{ s.lowerBound, s.upperBound };
  SecantPoint        p = evaluate(std::clamp(start, s.lowerBound, s.upperBound));
  SecantPoint        previous = p;
  double             curvature = s.curvatureGuess;
  bool               haveBest = false;
  r.evaluations = 1;
  r.curvature = curvature;
  for (;;)
  {
    CheckFinite(p);
    if (p.exact || !refine)
    {
      r.best = !haveBest || Better(p, r.best) ? p : r.best;
      haveBest = true;
    }
    const bool  onBound = (p.x <= s.lowerBound && p.derivative > 0.0) || (p.x >= s.upperBound && p.derivative < 0.0);
    std::string stop = std::abs(p.derivative) <= s.derivativeTolerance ? "the derivative is within the tolerance"
                       : onBound                                       ? "the minimum lies on a bound"
                                                                       : "";
    // The bracket and the secant take the point only once it is final: an inexact point the search would stop on
    // is refined first, so that its derivative's error (whose sign may be wrong near the minimum) shapes neither.
    Bracket trialBracket = bracket;
    double  trialCurvature = curvature;
    double  next = p.x;
    if (stop.empty())
    {
      next = SecantStep(p, r.evaluations > 1 ? &previous : nullptr, s.maximumStep, trialBracket, trialCurvature);
      stop = std::abs(next - p.x) < s.stepTolerance  ? "the next step is below the step tolerance"
             : r.evaluations >= s.maximumEvaluations ? "the maximum number of evaluations is reached"
                                                     : "";
    }
    if (!stop.empty() && !p.exact && refine)
    {
      p = refine(p.x); // decide again on the exact point
      p.exact = true;
      ++r.refinements;
      continue;
    }
    bracket = trialBracket;
    curvature = trialCurvature;
    r.curvature = curvature;
    if (!stop.empty())
    {
      r.onBound = onBound && std::abs(p.derivative) > s.derivativeTolerance;
      r.stopCondition = stop;
      break;
    }
    previous = p;
    p = evaluate(next);
    ++r.evaluations;
  }
  return r;
}

} // namespace bmr

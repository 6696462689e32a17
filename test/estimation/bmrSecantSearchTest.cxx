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
// bmr::SecantSearch, the outer search over log E of one unknown modulus, on functions with known minima:
// - a parabola with its curvature as the guess: one step lands on the minimum (to rounding, 1e-12);
// - f = e^x - 2x from -1 without a guess: converges to ln 2 (1e-12), superlinearly (errors e_{k+1} <= e_k^1.3
//   once below 0.1: the secant's order is 1.618, 1.3 leaves room for the first steps), in at most 10
//   evaluations (three steps of maximumStep 0.5 before the secant takes over, then six to rounding);
// - log cosh(x - 1), whose derivative saturates, so that the plain secant from far points overshoots:
//   the bracket keeps every step inside [a, b] and between sampled signs, and it still converges (1e-8);
// - minima beyond a bound end on that bound, flagged;
// - inexact points (f' off by up to half the derivative tolerance, as a loose inner solve's): the search steps
//   from them, stops only on an exact one (refined at the same x), and ends within the tolerance of the minimum,
//   as it does on exact points;
// - bad settings and non-finite derivatives are refused by name.
#include "bmrSecantSearch.h"
#include "bmrTestUtilities.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <vector>

namespace {
using bmr::test::Expect;
using bmr::test::ToString;

/** Evaluates f and f' and keeps every x asked for. */
struct Recorder
{
  std::function<double(double)> f, df;
  std::vector<double>           xs;
  bmr::SecantPoint
  operator()(double x)
  {
    xs.push_back(x);
    return { x, f(x), df(x) };
  }
};

bool
ParabolaInOneStep()
{
  const double              c = 3.7, minimum = 0.42;
  Recorder                  parabola{ [&](double x) { return 0.5 * c * (x - minimum) * (x - minimum); },
                     [&](double x) { return c * (x - minimum); } };
  bmr::SecantSearchSettings s;
  s.lowerBound = -2.0;
  s.upperBound = 2.0;
  s.curvatureGuess = c;
  s.derivativeTolerance = 1e-9;
  const auto r = bmr::SecantSearch(std::ref(parabola), 0.1, s);
  bool       ok =
    Expect(r.evaluations == 2, "parabola: 2 evaluations with the exact curvature, got " + ToString(r.evaluations));
  ok &= Expect(std::abs(r.best.x - minimum) < 1e-12, "parabola: minimum to 1e-12, got " + ToString(r.best.x));
  return ok && Expect(!r.onBound, "parabola: not on a bound");
}

bool
SuperlinearWithoutGuess()
{
  Recorder f{ [](double x) { return std::exp(x) - 2.0 * x; }, [](double x) { return std::exp(x) - 2.0; } };
  bmr::SecantSearchSettings s;
  s.lowerBound = -3.0;
  s.upperBound = 3.0;
  s.stepTolerance = 1e-12;
  s.derivativeTolerance = 1e-13;
  const auto   r = bmr::SecantSearch(std::ref(f), -1.0, s);
  const double minimum = std::log(2.0);
  bool         ok = Expect(std::abs(r.best.x - minimum) < 1e-12, "e^x - 2x: ln 2 to 1e-12, got " + ToString(r.best.x));
  ok &= Expect(r.evaluations <= 10, "e^x - 2x: at most 10 evaluations, got " + ToString(r.evaluations));
  for (std::size_t k = 1; k + 1 < f.xs.size(); ++k)
  {
    const double e0 = std::abs(f.xs[k] - minimum), e1 = std::abs(f.xs[k + 1] - minimum);
    if (e0 < 0.1 && e0 > 1e-9)
    {
      ok &= Expect(e1 <= std::pow(e0, 1.3),
                   "e^x - 2x: error " + ToString(e1) + " after " + ToString(e0) + " is superlinear (<= e^1.3)");
    }
  }
  return ok;
}

bool
BracketKeepsSteps()
{
  Recorder f{ [](double x) { return std::log(std::cosh(x - 1.0)); }, [](double x) { return std::tanh(x - 1.0); } };
  bmr::SecantSearchSettings s;
  s.lowerBound = -10.0;
  s.upperBound = 10.0;
  s.maximumStep = 8.0;
  s.stepTolerance = 1e-10;
  s.derivativeTolerance = 1e-12;
  s.maximumEvaluations = 60;
  const auto r = bmr::SecantSearch(std::ref(f), -6.0, s);
  bool       ok = Expect(std::abs(r.best.x - 1.0) < 1e-8, "log cosh: minimum 1 to 1e-8, got " + ToString(r.best.x));
  for (double x : f.xs)
  {
    ok &= Expect(x >= s.lowerBound && x <= s.upperBound, "log cosh: every trial inside the bounds, got " + ToString(x));
  }
  return ok;
}

bool
MinimumBeyondBounds()
{
  bool ok = true;
  for (const double minimum : { 5.0, -5.0 })
  {
    Recorder                  f{ [&](double x) { return (x - minimum) * (x - minimum); },
                [&](double x) { return 2.0 * (x - minimum); } };
    bmr::SecantSearchSettings s;
    s.lowerBound = -1.0;
    s.upperBound = 1.0;
    s.maximumStep = 0.3;
    const auto   r = bmr::SecantSearch(std::ref(f), 0.0, s);
    const double bound = minimum > 0.0 ? s.upperBound : s.lowerBound;
    ok &= Expect(r.onBound && r.best.x == bound,
                 "minimum at " + ToString(minimum) + ": ends on the bound " + ToString(bound) + ", got " +
                   ToString(r.best.x) + (r.onBound ? " (flagged)" : " (not flagged)"));
  }
  return ok;
}

bool
InexactPointsRefined()
{
  bool ok = true;
  // f = e^x - 2x; an inexact f' is off by a bias of either sign or by an error that changes with x.
  const std::function<double(double)> errors[] = { [](double) { return 0.5e-6; },
                                                   [](double) { return -0.5e-6; },
                                                   [](double x) { return 0.5e-6 * std::sin(1e7 * x); } };
  for (const auto & error : errors)
  {
    const auto                df = [](double x) { return std::exp(x) - 2.0; };
    std::vector<double>       refined;
    bmr::SecantSearchSettings s;
    s.lowerBound = -3.0;
    s.upperBound = 3.0;
    s.stepTolerance = 0.0;
    s.derivativeTolerance = 1e-6;
    const auto inexact = [&](double x) {
      return bmr::SecantPoint{ x, std::exp(x) - 2.0 * x, df(x) + error(x), false };
    };
    const auto exact = [&](double x) {
      refined.push_back(x);
      return bmr::SecantPoint{ x, std::exp(x) - 2.0 * x, df(x) };
    };
    const auto   r = bmr::SecantSearch(inexact, -1.0, s, exact);
    const double minimum = std::log(2.0);
    const auto   what = "inexact f' off by " + ToString(error(1.0)) + " at x = 1: ";
    std::cout << what << r.evaluations << " evaluations, " << r.refinements << " refinements, " << r.stopCondition
              << std::endl;
    ok &= Expect(r.refinements >= 1 && !refined.empty() && refined.back() == r.best.x,
                 what + "ends on a refined point (refinements " + ToString(r.refinements) + ")");
    ok &= Expect(r.best.exact && std::abs(df(r.best.x)) <= s.derivativeTolerance,
                 what + "|f'| within the tolerance at the end, got " + ToString(df(r.best.x)));
    // |f'| <= 1e-6 with f''(ln 2) = 2: within 5e-7 of the minimum.
    ok &= Expect(std::abs(r.best.x - minimum) <= 5.1e-7, what + "ln 2 to 5e-7, got " + ToString(r.best.x));
  }
  return ok;
}

bool
BadInputRefused()
{
  bmr::SecantSearchSettings bounds;
  bounds.lowerBound = 1.0;
  bounds.upperBound = 1.0;
  const auto constant = [](double x) { return bmr::SecantPoint{ x, 0.0, 1.0 }; };
  bool       ok = bmr::test::ExpectException(
    "empty interval", [&] { bmr::SecantSearch(constant, 1.0, bounds); }, "lower < upper");
  bmr::SecantSearchSettings s;
  ok &= bmr::test::ExpectException(
    "NaN derivative",
    [&] {
      bmr::SecantSearch([](double x) { return bmr::SecantPoint{ x, 1.0, std::nan("") }; }, 0.5, s);
    },
    "not finite");
  s.maximumStep = 0.0;
  ok &= bmr::test::ExpectException(
    "zero step", [&] { bmr::SecantSearch(constant, 0.5, s); }, "positive maximum step");
  return ok;
}
} // namespace

int
bmrSecantSearchTest(int, char *[])
{
  bool ok = ParabolaInOneStep();
  ok &= SuperlinearWithoutGuess();
  ok &= BracketKeepsSteps();
  ok &= MinimumBeyondBounds();
  ok &= InexactPointsRefined();
  ok &= BadInputRefused();
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

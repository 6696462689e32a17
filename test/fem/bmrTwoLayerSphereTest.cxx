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
// Two-layer elastic sphere under external pressure against the closed form
// (bmr::TwoLayerSphereSolution): accuracy at the default mesh over nu <= 0.45 and
// stiffness ratios 1e-3 ... 1e3, near incompressibility (nu 0.49, 0.499) with the nodal-averaged
// pressure formulation, and the L2 convergence order under refinement.
#include "bmrTestUtilities.h"
#include "bmrTwoLayerSphereCase.h"

#include <cmath>
#include <cstdlib>
#include <iostream>

using namespace bmr::test;

int
bmrTwoLayerSphereTest(int, char *[])
{
  bool ok = true;
  // 1. Accuracy at the default mesh (cell size 0.5 mm: ~10 elements through the 5 mm shell): radial error <= 1 %.
  //    The soft-core cases are the hardest: the shell then carries the whole load and bends inwards.
  const bmr::TetrahedralMesh mesh = SphereMesh(0.5);
  std::cout << "default mesh: " << mesh.GetNumberOfTetrahedra() << " tetrahedra" << std::endl;
  for (double nu : { 0.3, 0.45 }) // the ends of the range nu <= 0.45 (0.4 lies between them)
  {
    for (double ratio : { 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3 })
    {
      const Errors err = Solve(mesh, 10.0 * ratio, nu, 10.0, 0.35);
      std::cout << "nu_core " << nu << " E_core/E_shell " << ratio << ": radial error " << 100 * err.nodalRadialRelative
                << " %, relative L2 " << 100 * err.l2Relative << " %" << std::endl;
      // 1 %: the accuracy requirement for the default mesh.
      ok &= Expect(err.nodalRadialRelative <= 0.01, "radial error at most 1 %");
    }
  }
  // 2. Near incompressibility, both layers at nu = 0.49 and 0.499 (lambda/mu = 49, 499), a core 10x stiffer
  //    and 10x softer than the shell: the shell's B/r^2 term is isochoric, which locked P1 tetrahedra cannot
  //    represent. With the nodal-averaged pressure formulation the radial error stays <= 2 % (the issue's
  //    requirement at the default mesh); the standard formulation's error is printed for comparison and
  //    must be the larger one at nu = 0.499 (locking is real, and the remedy removes it).
  for (double nu : { 0.49, 0.499 })
  {
    for (double ratio : { 0.1, 10.0 })
    {
      const Errors averaged = Solve(mesh, 10.0 * ratio, nu, 10.0, nu, true);
      const Errors standard = Solve(mesh, 10.0 * ratio, nu, 10.0, nu, false);
      std::cout << "nu " << nu << " E_core/E_shell " << ratio << ": radial error, nodal-averaged pressure "
                << 100 * averaged.nodalRadialRelative << " %, standard P1 " << 100 * standard.nodalRadialRelative
                << " %" << std::endl;
      ok &= Expect(averaged.nodalRadialRelative <= 0.02,
                   "radial error at most 2 % with the nodal-averaged pressure formulation");
      ok &= Expect(nu != 0.499 || standard.nodalRadialRelative > averaged.nodalRadialRelative,
                   "at nu = 0.499 the standard formulation is less accurate than the nodal-averaged one");
    }
  }
  // 3. L2 convergence order over three refinements (P1 elements: order 2 expected).
  const double        sizes[] = { 2.0, 1.6, 1.25, 1.0 };
  std::vector<double> logh, loge;
  for (double h : sizes)
  {
    const bmr::TetrahedralMesh m = SphereMesh(h);
    const double               hMean = bmr::ComputeMeshQuality(m).meanEdgeLength;
    const Errors               err = Solve(m, 50.0, 0.4, 10.0, 0.35);
    std::cout << "h " << h << " (mean edge " << hMean << " mm, " << m.GetNumberOfTetrahedra() << " tets): L2 error "
              << err.l2 << std::endl;
    logh.push_back(std::log(hMean));
    loge.push_back(std::log(err.l2));
  }
  double mh = 0, me = 0;
  for (std::size_t i = 0; i < logh.size(); ++i)
  {
    mh += logh[i] / logh.size();
    me += loge[i] / loge.size();
  }
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < logh.size(); ++i)
  {
    sxy += (logh[i] - mh) * (loge[i] - me);
    sxx += (logh[i] - mh) * (logh[i] - mh);
  }
  const double order = sxy / sxx;
  std::cout << "observed L2 convergence order " << order << std::endl;
  // >= 1.8: P1 elements converge with order 2 in L2; 0.2 allows for unstructured, non-nested meshes.
  ok &= Expect(order >= 1.8, "convergence order at least 1.8");
  return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

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
// Extreme cases on the two-layer sphere with a closed form (benchmark, not a test; run by
// benchmarks/run_extreme_cases.sh): stiffness ratios 1e-3 ... 1e3, Poisson's ratios 0.3 ... 0.499 with the
// standard and the nodal-averaged pressure formulation, very coarse / default / fine meshes and a mesh with
// slivers. One CSV row per case: radial error against the closed form, residual, mesh quality, time and a
// verdict (ok: error <= 2 %; warned: the library warns about the case: nu > 0.45 on standard P1, a layer
// fewer than bmr::MinimumElementsAcross elements across;
// inaccurate: error above 2 % without a warning; refused: the library threw, with its message).
#include "bmrSimulation.h"
#include "bmrTwoLayerSphereCase.h"
#include "itkMacro.h"

#include <chrono>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>

using namespace bmr::test;

namespace {
struct Case
{
  std::string group;
  double      h;
  bool        optimize;
  double      ratio; // E_core / E_shell
  double      nu;    // both layers
  bool        averaged;
};
} // namespace

int
main(int argc, char * argv[])
{
  if (argc < 2)
  {
    std::cerr << "usage: bmrExtremeCasesBenchmark OUT.csv" << std::endl;
    return 2;
  }
  std::vector<Case> cases;
  for (double ratio : { 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3 })
  {
    cases.push_back({ "stiffness ratio", 0.5, true, ratio, 0.4, false });
  }
  for (double nu : { 0.3, 0.45, 0.49, 0.499 })
  {
    for (bool averaged : { false, true })
    {
      cases.push_back({ "poisson ratio", 0.5, true, 10.0, nu, averaged });
    }
  }
  for (double h : { 2.5, 1.0, 0.35 })
  {
    cases.push_back({ "mesh size", h, true, 10.0, 0.4, false });
  }
  cases.push_back({ "slivers (no perturb/exude)", 0.5, false, 10.0, 0.4, false });
  cases.push_back({ "slivers (no perturb/exude)", 0.5, false, 10.0, 0.499, true });

  std::ofstream csv(argv[1]);
  csv << "# two-layer sphere, inner radius 5 mm, outer 10 mm, 1 kPa external pressure, shell E 10 kPa\n"
      << "group,cell_size_mm,optimized,E_ratio,nu,formulation,tetrahedra,min_dihedral_deg,min_elements_across,"
         "radial_error,relative_L2_error,residual,seconds,verdict,reason\n";
  std::cout << "| group | h [mm] | E ratio | nu | formulation | tets | min dihedral | elements across | radial error | "
               "residual | time [s] | verdict |\n"
            << "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|\n";
  std::map<std::pair<double, bool>, bmr::TetrahedralMesh> meshes;
  for (const Case & c : cases)
  {
    const auto  start = std::chrono::steady_clock::now();
    std::string verdict, reason;
    Errors      e{ 0, 0, 0, 0 };
    std::size_t tets = 0;
    double      dihedral = 0.0;
    double      across = 0.0;
    try
    {
      const auto key = std::make_pair(c.h, c.optimize);
      if (!meshes.count(key))
      {
        meshes[key] = SphereMesh(c.h, c.optimize);
      }
      const bmr::TetrahedralMesh & mesh = meshes[key];
      tets = mesh.GetNumberOfTetrahedra();
      dihedral = bmr::ComputeMeshQuality(mesh).minimumDihedralAngleDegrees;
      e = Solve(mesh, 10.0 * c.ratio, c.nu, 10.0, c.nu, c.averaged);
      bmr::Scene scene;
      scene.labels = { { "shell", 1, bmr::LabelRoleEnum::Material, 10.0, c.nu },
                       { "core", 2, bmr::LabelRoleEnum::Material, 10.0 * c.ratio, c.nu } };
      scene.formulation =
        c.averaged ? bmr::ElementFormulationEnum::NodalAveragedPressure : bmr::ElementFormulationEnum::Standard;
      across = std::numeric_limits<double>::infinity();
      for (const bmr::LabelResolution & r : bmr::ComputeLabelResolution(mesh))
      {
        across = std::min(across, r.elementsAcross);
      }
      std::vector<std::string> warnings = scene.Warnings();
      for (const std::string & w : bmr::MeshResolutionWarnings(scene, mesh))
      {
        warnings.push_back(w);
      }
      const bool        warned = !warnings.empty();
      const std::string what = warned ? warnings.front() : "";
      if (!std::isfinite(e.nodalRadialRelative))
      {
        verdict = "FAILED";
        reason = "non-finite result";
      }
      else if (e.nodalRadialRelative <= 0.02)
      {
        verdict = warned ? "warned" : "ok";
        reason = warned ? what + " (accurate here)" : "";
      }
      else
      {
        verdict = warned ? "warned" : "inaccurate";
        reason = warned ? what : "error above 2 %";
      }
    }
    catch (const itk::ExceptionObject & x)
    {
      verdict = "refused";
      reason = x.GetDescription();
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const char * formulation = c.averaged ? "nodal_averaged_pressure" : "standard";
    csv << c.group << "," << c.h << "," << c.optimize << "," << c.ratio << "," << c.nu << "," << formulation << ","
        << tets << "," << dihedral << "," << across << "," << e.nodalRadialRelative << "," << e.l2Relative << ","
        << e.residual << "," << seconds << "," << verdict << ",\"" << reason << "\"\n";
    std::cout << "| " << c.group << " | " << c.h << " | " << c.ratio << " | " << c.nu << " | " << formulation << " | "
              << tets << " | " << std::fixed << std::setprecision(2) << dihedral << " | " << std::setprecision(1)
              << across << " | " << std::setprecision(3) << 100.0 * e.nodalRadialRelative << " % | " << std::scientific
              << std::setprecision(1) << e.residual << " | " << std::fixed << std::setprecision(2) << seconds << " | "
              << verdict << (reason.empty() ? "" : ": " + reason) << " |" << std::defaultfloat << std::setprecision(6)
              << std::endl;
  }
  return 0;
}

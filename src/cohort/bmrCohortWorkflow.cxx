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
#include "bmrCohort.h"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace bmr {

std::string
CohortWorkflowConfigJson(const Cohort & cohort, const CohortWorkflowSettings & settings)
{
  // Absolute paths: Snakemake runs every job from the study directory, not from where the cohort file is.
  const auto absolute = [](const std::string & path) {
    return std::filesystem::absolute(path).lexically_normal().string();
  };
  nlohmann::ordered_json jobs = nlohmann::ordered_json::object();
  for (const CohortFraction & f : cohort.fractions)
  {
    jobs[f.Key()] = { { "patient", f.patient },
                      { "fraction", f.fraction },
                      { "planning_ct", absolute(f.planningCT) },
                      { "planning_labels", absolute(f.planningLabels) },
                      { "daily_ct", absolute(f.dailyCT) },
                      { "daily_labels", absolute(f.dailyLabels) },
                      { "scene", absolute(f.scene) } };
  }
  nlohmann::ordered_json j;
  j["cohort"] = absolute(cohort.path);
  j["biomechreg"] = settings.executable;
  j["register_options"] = settings.registerOptions;
  j["threads_per_job"] = settings.threadsPerJob;
  j["mem_mb"] = settings.memoryMB;
  j["runtime_min"] = settings.runtimeMinutes;
  j["jobs"] = jobs;
  return j.dump(2) + "\n";
}

} // namespace bmr

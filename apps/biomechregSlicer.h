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
// biomechreg as 3D Slicer command-line modules: run under another name (a link in the build's slicer/ folder,
// BiomechanicalRegistration -> biomechreg), it describes itself on --xml in Slicer's execution-model XML and takes
// Slicer's arguments, which it maps to a subcommand's options.
#ifndef biomechregSlicer_h
#define biomechregSlicer_h

#include "biomechregCommon.h"

#include <functional>
#include <string>
#include <vector>

namespace bmrcli {

/** One parameter of a module's description; where it goes on biomechreg's command line. */
struct SlicerParameter
{
  const char *              tag{ "" };  ///< element: image, transform, file, pointfile, integer, double, ...
  const char *              name{ "" }; ///< also the longflag (Slicer's names: [_a-zA-Z][_a-zA-Z0-9]*)
  const char *              label{ "" };
  const char *              description{ "" };
  const char *              channel{ "" }; ///< "input" or "output" (empty: a setting)
  const char *              type{ "" };    ///< image/transform/pointfile type attribute, or empty
  const char *              option{ "" };  ///< the biomechreg option it sets; empty for outputs and return values
  const char *              file{ "" };    ///< output: the file biomechreg writes into --out that Slicer gets
  const char *              defaultValue{ "" };
  std::vector<const char *> elements; ///< enumeration values
  const char *              minimum{ "" };
  const char *              maximum{ "" };
};

struct SlicerGroup
{
  const char *                 label;
  bool                         advanced;
  std::vector<SlicerParameter> parameters;
};

/** A module: its executable's name, the subcommand it runs, its description and parameters. Return parameters
 * (channel output, no option, no file) are read from the run's report.json (returnKey: "modulus", "statement"). */
struct SlicerModule
{
  const char *             executable;
  const char *             command;
  const char *             title;
  const char *             description;
  std::vector<SlicerGroup> groups;
};

/** The modules, by executable name. */
const std::vector<SlicerModule> &
SlicerModules();

/** The module run as \a argv0 (its file name), or nullptr when biomechreg runs under its own name. */
const SlicerModule *
FindSlicerModule(const char * argv0);

/** The module's description, as Slicer reads it on --xml. */
std::string
SlicerModuleXml(const SlicerModule & module);

using SubcommandRunner = std::function<int(const std::string & command, const Arguments & options)>;

/** Runs \a module with Slicer's \a args: --xml prints the description; otherwise the subcommand runs with the
 * mapped options into a scratch directory, reporting its stages in Slicer's progress tags, and its outputs are
 * moved to the paths Slicer gave, the return parameters written to --returnparameterfile. An argument the
 * description does not list is a UsageError. */
int
RunSlicerModule(const SlicerModule & module, const std::vector<std::string> & args, const SubcommandRunner & run);

} // namespace bmrcli

#endif

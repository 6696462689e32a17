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
#include "biomechregSlicer.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <utility>
#include <unistd.h>

namespace bmrcli {

namespace {
namespace fs = std::filesystem;

// The parameters' kinds; every field not set is empty.
SlicerParameter
Parameter(const char * tag, const char * name, const char * label, const char * description)
{
  SlicerParameter p;
  p.tag = tag;
  p.name = name;
  p.label = label;
  p.description = description;
  return p;
}

/** An input file (image, transform, file, pointfile) passed to biomechreg as \a option. */
SlicerParameter
Input(const char * tag,
      const char * type,
      const char * name,
      const char * label,
      const char * option,
      const char * description)
{
  SlicerParameter p = Parameter(tag, name, label, description);
  p.channel = "input";
  p.type = type;
  p.option = option;
  return p;
}

/** An output file: biomechreg's \a file in its --out directory, moved to the path Slicer gives. */
SlicerParameter
Output(const char * tag,
       const char * type,
       const char * name,
       const char * label,
       const char * file,
       const char * description)
{
  SlicerParameter p = Parameter(tag, name, label, description);
  p.channel = "output";
  p.type = type;
  p.file = file;
  return p;
}

/** A setting passed as \a option, with its default and, for numbers, its range. */
SlicerParameter
Setting(const char * tag,
        const char * name,
        const char * label,
        const char * option,
        const char * defaultValue,
        const char * description,
        const char * minimum = "",
        const char * maximum = "")
{
  SlicerParameter p = Parameter(tag, name, label, description);
  p.option = option;
  p.defaultValue = defaultValue;
  p.minimum = minimum;
  p.maximum = maximum;
  return p;
}

SlicerParameter
Enumeration(const char *              name,
            const char *              label,
            const char *              option,
            std::vector<const char *> elements,
            const char *              description)
{
  SlicerParameter p = Setting("string-enumeration", name, label, option, elements.front(), description);
  p.elements = std::move(elements);
  return p;
}

/** A value returned to Slicer through --returnparameterfile (read from the run's report.json). */
SlicerParameter
Returned(const char * tag, const char * name, const char * label, const char * description)
{
  SlicerParameter p = Parameter(tag, name, label, description);
  p.channel = "output";
  return p;
}

SlicerParameter
Field(const char * channel, const char * name, const char * option, const char * file)
{
  const char * description =
    "fixed -> moving [mm, LPS] on the fixed grid: the resampling transform of the moving images";
  SlicerParameter p = std::string(channel) == "input"
                        ? Input("transform", "nonlinear", name, "Displacement field", option, description)
                        : Output("transform", "nonlinear", name, "Displacement field", file, description);
  return p;
}

SlicerParameter
SceneFile()
{
  return Input("file",
               "",
               "scene",
               "Scene",
               "--scene",
               "The scene JSON: labels, roles, materials, loads, objective (docs/scenes.md)");
}

SlicerParameter
Threads()
{
  return Setting("integer",
                 "threads",
                 "Threads",
                 "--threads",
                 "0",
                 "The library's threads (0: all cores); the results do not depend on it",
                 "0",
                 "256");
}

/** The register module's inputs: the two scans' CT and labels, and the scene or the labels' names. */
std::vector<SlicerParameter>
RegistrationInputs()
{
  return { Input("image", "scalar", "movingCT", "Moving CT", "--moving-ct", "The planning CT [HU]"),
           Input("image",
                 "label",
                 "movingLabels",
                 "Moving labels",
                 "--moving-labels",
                 "The planning scan's organs, labelled as the scene says"),
           Input("image", "scalar", "fixedCT", "Fixed CT", "--fixed-ct", "The daily CT [HU]"),
           Input(
             "image", "label", "fixedLabels", "Fixed labels", "--fixed-labels", "The daily scan's organs, on its grid"),
           SceneFile(),
           Input("file",
                 "",
                 "movingLabelNames",
                 "Moving label names",
                 "--moving-label-names",
                 "Instead of a scene (register only): the moving labels' names, a color table or value,name CSV with "
                 "TG-263 names (Prostate, Bladder, Rectum, External), for the built-in pelvis scene"),
           Input("file",
                 "",
                 "fixedLabelNames",
                 "Fixed label names",
                 "--fixed-label-names",
                 "Without a scene: the fixed labels' names, as for the moving labels") };
}

SlicerModule
RegistrationModule()
{
  return {
    "BiomechanicalRegistration",
    "register",
    "Biomechanical Registration",
    "Physics-based registration of segmented CT with joint estimation of an organ's Young's modulus "
    "(biomechreg register): the moving labels meshed, the scene's wall loads and the unknown modulus fitted "
    "so that the simulated organs match the fixed labels.",
    { { "Inputs", false, RegistrationInputs() },
      { "Estimation",
        false,
        { Enumeration("uncertainty",
                      "Uncertainty",
                      "--uncertainty",
                      { "rescan", "bootstrap", "curvature", "none" },
                      "How the modulus' interval is stated"),
          Setting(
            "integer", "resamples", "Resamples", "--resamples", "4", "Re-estimations of the interval", "3", "1000"),
          Enumeration("wallMotion",
                      "Wall motion",
                      "--wall-motion",
                      { "normal", "free", "traction", "pressure" },
                      "How the hollow organs' walls move"),
          Setting("double",
                  "meshScale",
                  "Mesh scale",
                  "--mesh-scale",
                  "1",
                  "Mesh sizes relative to the scene's (> 1: coarser, faster)",
                  "0.25",
                  "4"),
          Threads() } },
      { "Outputs",
        false,
        { Field("output", "outputField", "", "field.nrrd"),
          Output("image",
                 "scalar",
                 "warpedCT",
                 "Warped CT",
                 "warped_ct.nrrd",
                 "The moving CT resampled onto the fixed grid"),
          Output("image",
                 "label",
                 "warpedLabels",
                 "Warped labels",
                 "warped_labels.nrrd",
                 "The moving labels resampled onto the fixed grid"),
          Output("file",
                 "",
                 "report",
                 "Report",
                 "report.json",
                 "report.json: moduli, intervals, distances, Dice, wall times"),
          Returned("double", "youngsModulus", "Young's modulus [kPa]", "The estimated modulus of the unknown organ"),
          Returned(
            "string", "modulusStatement", "Statement", "The estimate with its interval, as register states it") } } }
  };
}

SlicerModule
SimulationModule()
{
  return { "BiomechanicalSimulation",
           "simulate",
           "Biomechanical Simulation",
           "The forward problem of a scene (biomechreg simulate): the labels meshed, the scene's known loads "
           "applied with finite elements, the displacement field and the warped images.",
           { { "Inputs",
               false,
               { Input("image", "label", "movingLabels", "Labels", "--moving-labels", "The anatomy's labels"),
                 Input("image", "scalar", "movingCT", "CT", "--moving-ct", "Warped too (optional)"),
                 SceneFile(),
                 Input("image",
                       "scalar",
                       "reference",
                       "Reference",
                       "--reference",
                       "The grid of the field (optional; default: the labels')"),
                 Threads() } },
             { "Outputs",
               false,
               { Field("output", "outputField", "", "field.nrrd"),
                 Output("image", "label", "warpedLabels", "Warped labels", "warped_labels.nrrd", "Nearest neighbour"),
                 Output("image", "scalar", "warpedCT", "Warped CT", "warped_ct.nrrd", "Linear (with a CT)") } } } };
}

SlicerModule
MarkersModule()
{
  return {
    "BiomechanicalMarkers",
    "markers",
    "Biomechanical Markers",
    "An organ's deformation from tracked markers (biomechreg markers): forces on the organ's surface fitted "
    "so that the planning markers move onto the treatment ones.",
    { { "Inputs",
        false,
        { Input("image", "scalar", "planningCT", "Planning CT", "--planning-ct", "The planning CT [HU]"),
          Input(
            "image", "label", "planningLabels", "Planning labels", "--planning-labels", "The planning scan's organs"),
          SceneFile(),
          Input("pointfile",
                "point",
                "planningMarkers",
                "Planning markers",
                "--planning-markers",
                "The markers on the planning scan"),
          Input("pointfile",
                "point",
                "treatmentMarkers",
                "Treatment markers",
                "--treatment-markers",
                "The same markers at treatment"),
          Setting("string", "organ", "Organ", "--organ", "prostate", "The organ whose surface carries the forces"),
          Setting("string",
                  "moduli",
                  "Moduli",
                  "--modulus",
                  "",
                  "Young's moduli of the scene's unknown labels: NAME=E_kPa,... (kPa)"),
          Threads() } },
      { "Outputs",
        false,
        { Field("output", "outputField", "", "field.nrrd"),
          Output("image", "scalar", "warpedCT", "Warped CT", "warped_ct.nrrd", "The planning CT deformed"),
          Output("image",
                 "label",
                 "warpedLabels",
                 "Warped labels",
                 "warped_labels.nrrd",
                 "The planning labels deformed") } } }
  };
}

SlicerModule
WarpModule()
{
  return {
    "BiomechanicalWarp",
    "warp",
    "Biomechanical Warp",
    "An image resampled through a displacement field (biomechreg warp, itk::ImageWarper): linear, or "
    "nearest neighbour for a label map.",
    { { "Inputs",
        false,
        { Input("image", "scalar", "inputVolume", "Image", "--image", "The image to warp"),
          Field("input", "inputField", "--field", ""),
          Setting("boolean",
                  "labels",
                  "Label map",
                  "--labels",
                  "false",
                  "Nearest neighbour (a label map) instead of linear") } },
      { "Outputs",
        false,
        { Output("image", "scalar", "outputVolume", "Warped image", "warped.nrrd", "On the field's grid") } } }
  };
}

std::string
Escaped(const std::string & text)
{
  std::string out;
  for (char c : text)
  {
    out += c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;" : std::string(1, c);
  }
  return out;
}

void
WriteParameter(std::ostream & xml, const SlicerParameter & p)
{
  xml << "    <" << p.tag;
  if (*p.type)
  {
    xml << " type=\"" << p.type << "\"";
  }
  if (std::string(p.tag) == "transform" || std::string(p.tag) == "image")
  {
    xml << " fileExtensions=\".nrrd\"";
  }
  xml << ">\n      <name>" << p.name << "</name>\n";
  const bool returned = std::string(p.channel) == "output" && !*p.option && !*p.file;
  if (!returned)
  {
    xml << "      <longflag>--" << p.name << "</longflag>\n";
  }
  xml << "      <label>" << Escaped(p.label) << "</label>\n      <description>" << Escaped(p.description)
      << "</description>\n";
  if (*p.channel)
  {
    xml << "      <channel>" << p.channel << "</channel>\n";
  }
  if (*p.defaultValue)
  {
    xml << "      <default>" << p.defaultValue << "</default>\n";
  }
  for (const char * element : p.elements)
  {
    xml << "      <element>" << element << "</element>\n";
  }
  if (*p.minimum)
  {
    xml << "      <constraints>\n        <minimum>" << p.minimum << "</minimum>\n        <maximum>" << p.maximum
        << "</maximum>\n        <step>1</step>\n      </constraints>\n";
  }
  xml << "    </" << p.tag << ">\n";
}

/** A scratch directory of its own for one run, removed with it. */
class ScratchDirectory
{
public:
  ScratchDirectory()
    : m_Path(fs::temp_directory_path() / ("biomechreg-slicer-" + std::to_string(getpid())))
  {
    fs::remove_all(m_Path);
    fs::create_directories(m_Path);
  }
  ~ScratchDirectory()
  {
    std::error_code ignored;
    fs::remove_all(m_Path, ignored);
  }
  ScratchDirectory(const ScratchDirectory &) = delete;
  ScratchDirectory &
  operator=(const ScratchDirectory &) = delete;
  const fs::path &
  Path() const
  {
    return m_Path;
  }

private:
  fs::path m_Path;
};

const SlicerParameter *
FindParameter(const SlicerModule & module, const std::string & flag)
{
  for (const auto & group : module.groups)
  {
    for (const auto & p : group.parameters)
    {
      if (flag == std::string("--") + p.name)
      {
        return &p;
      }
    }
  }
  return nullptr;
}

/** What Slicer asked for, as biomechreg options; the outputs to move and the return parameters' file. */
struct SlicerCall
{
  std::vector<std::string>                         options;
  unsigned int                                     threads{ 0 };
  std::vector<std::pair<std::string, std::string>> outputs; ///< file in --out, the path Slicer reads
  std::string                                      returnParameterFile;
};

SlicerCall
TranslateArguments(const SlicerModule & module, const std::vector<std::string> & args)
{
  SlicerCall call;
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string &     flag = args[i];
    const SlicerParameter * p = FindParameter(module, flag);
    const bool              flagOnly = p != nullptr && std::string(p->tag) == "boolean";
    if ((p == nullptr && flag != "--returnparameterfile" && flag != "--processinformationaddress") ||
        (!flagOnly && i + 1 == args.size()))
    {
      throw UsageError(module.executable + std::string(": unknown argument or missing value: \"") + flag + "\"");
    }
    const std::string value = flagOnly ? "" : args[++i];
    if (p == nullptr)
    {
      call.returnParameterFile = flag == "--returnparameterfile" ? value : call.returnParameterFile;
    }
    else if (*p->file)
    {
      call.outputs.emplace_back(p->file, value);
    }
    else if (std::string(p->option) == "--threads")
    {
      call.threads = static_cast<unsigned int>(std::stoul(value));
    }
    else if (flagOnly)
    {
      call.options.insert(call.options.end(), { p->option, "on" });
    }
    else
    {
      call.options.insert(call.options.end(), { p->option, value });
    }
  }
  return call;
}

/** The register report's modulus and statement, as Slicer's "name = value" lines. */
void
WriteReturnParameters(const fs::path & report, const std::string & path)
{
  std::ifstream        in(report);
  const nlohmann::json j = nlohmann::json::parse(in);
  std::ofstream        out(path);
  for (const auto & [name, modulus] : j.at("youngs_modulus_kPa").items())
  {
    out << "youngsModulus = " << modulus.get<double>() << "\n";
    const auto & intervals = j.at("youngs_modulus_interval");
    out << "modulusStatement = "
        << (intervals.contains(name) ? intervals.at(name).at("statement").get<std::string>() : std::string()) << "\n";
    break; // the scene's first unknown organ
  }
}
} // namespace

const std::vector<SlicerModule> &
SlicerModules()
{
  static const std::vector<SlicerModule> modules = {
    RegistrationModule(), SimulationModule(), MarkersModule(), WarpModule()
  };
  return modules;
}

const SlicerModule *
FindSlicerModule(const char * argv0)
{
  const std::string name = fs::path(argv0).filename().string();
  for (const auto & module : SlicerModules())
  {
    if (name == module.executable)
    {
      return &module;
    }
  }
  return nullptr;
}

std::string
SlicerModuleXml(const SlicerModule & module)
{
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<executable>\n  <category>Registration.Biomechanical</category>\n"
      << "  <title>" << module.title << "</title>\n  <description>" << Escaped(module.description)
      << "</description>\n  <version>" << BMR_VERSION << "</version>\n"
      << "  "
         "<documentation-url>https://github.com/InsightSoftwareConsortium/ITKBiomechanicalRegistration</"
         "documentation-url>\n"
      << "  <license>GPL-3.0-or-later (the built binary; the source is Apache-2.0)</license>\n"
      << "  <contributor>ITKBiomechanicalRegistration</contributor>\n"
      << "  <acknowledgements>The method of H.-P. Lee, Simulation-Based Joint Estimation of Body Deformation and "
         "Elasticity Parameters for Medical Image Analysis (UNC, 2012).</acknowledgements>\n";
  for (const auto & group : module.groups)
  {
    xml << "  <parameters" << (group.advanced ? " advanced=\"true\"" : "") << ">\n    <label>" << group.label
        << "</label>\n    <description>" << group.label << "</description>\n";
    for (const auto & p : group.parameters)
    {
      WriteParameter(xml, p);
    }
    xml << "  </parameters>\n";
  }
  xml << "</executable>\n";
  return xml.str();
}

int
RunSlicerModule(const SlicerModule & module, const std::vector<std::string> & args, const SubcommandRunner & run)
{
  if (args.size() == 1 && args[0] == "--xml")
  {
    std::cout << SlicerModuleXml(module);
    return EXIT_SUCCESS;
  }
  SlicerCall    call = TranslateArguments(module, args);
  GlobalOptions global;
  global.threads = call.threads;
  ApplyGlobalOptions(global);
  UseSlicerProgress();
  const ScratchDirectory scratch;
  call.options.insert(call.options.end(), { "--out", scratch.Path().string() });
  const int status = run(module.command, Arguments(call.options));
  for (const auto & [file, destination] : call.outputs)
  {
    if (!fs::exists(scratch.Path() / file))
    {
      throw UsageError(std::string(module.executable) + ": the run wrote no " + file + " (is its input given?)");
    }
    fs::copy_file(scratch.Path() / file, destination, fs::copy_options::overwrite_existing);
  }
  if (!call.returnParameterFile.empty() && fs::exists(scratch.Path() / "report.json") &&
      std::string(module.command) == "register")
  {
    WriteReturnParameters(scratch.Path() / "report.json", call.returnParameterFile);
  }
  return status;
}

} // namespace bmrcli

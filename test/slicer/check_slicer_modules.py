#!/usr/bin/env python3
"""3D Slicer's view of biomechreg's CLI modules (ctest slicer_modules): for every module in the build's slicer/
folder, what Slicer does with it.

1. `MODULE --xml` (Slicer waits 5 s) prints a description that starts with <?xml, validates against the project's
   schema (xmllint --schema test/slicer/ModuleDescription.xsd) and names every parameter with a label and a
   longflag, or none for a return value, its longflags unique.
2. A simulated Slicer run: every longflag of the description, with its default or a value for a small pelvis
   phantom, inputs and outputs as files, and --returnparameterfile when the module returns values, as Slicer
   builds the command line. It must exit 0, print <filter-start> and <filter-end> (register also
   <filter-progress>), write every output it was given and the return values (name = value lines).
3. An argument the description does not list: exit status 2 and one line on stderr.

Usage: check_slicer_modules.py BUILD_DIR SCHEMA SCRATCH_DIR"""

import pathlib
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET


def phantom(cli, out, *options):
    subprocess.run([cli, "phantom", *options, "--out", str(out)], check=True, stdout=subprocess.DEVNULL)
    return out


def input_values(module, p, s):
    """A value for every input a module may take: from the small pelvis phantom in directory p (with seeds), or
    for registration from the spheres phantom in s (1 mm voxels, at which register states an interval, whose
    rescans report progress)."""
    if module.name.endswith("Registration"):
        p = s
    return {"movingCT": p / "moving_ct.nrrd", "movingLabels": p / "moving_labels.nrrd",
            "fixedCT": p / "fixed_ct.nrrd", "fixedLabels": p / "fixed_labels.nrrd", "scene": p / "scene.json",
            "reference": p / "fixed_ct.nrrd", "planningCT": p / "moving_ct.nrrd",
            "planningLabels": p / "moving_labels.nrrd", "planningMarkers": p / "landmarks_moving.csv",
            "treatmentMarkers": p / "landmarks_tracked.csv", "inputVolume": p / "moving_ct.nrrd",
            "inputField": p / "truth_field.nrrd", "moduli": "prostate=60", "resamples": "3"}


def description(module):
    xml = subprocess.run([str(module), "--xml"], capture_output=True, text=True, timeout=5, check=True).stdout
    if not xml.startswith("<?xml"):
        raise SystemExit("%s --xml: the output does not start with <?xml" % module.name)
    return xml


def validate(module, xml, schema):
    run = subprocess.run(["xmllint", "--noout", "--schema", str(schema), "-"], input=xml, capture_output=True,
                         text=True)
    if run.returncode != 0:
        raise SystemExit("%s: the description does not validate:\n%s" % (module.name, run.stderr))


def parameters(module, xml):
    """(tag, name, longflag, channel, default) of every parameter; checks names, labels and flags."""
    found, flags = [], set()
    for group in ET.fromstring(xml).iter("parameters"):
        for p in group:
            if p.tag in ("label", "description"):
                continue
            name, label = p.findtext("name"), p.findtext("label")
            longflag, channel = p.findtext("longflag"), p.findtext("channel")
            if not name or not label:
                raise SystemExit("%s: a %s without a name or a label" % (module.name, p.tag))
            if longflag is None and channel != "output":
                raise SystemExit("%s: %s has no longflag and is no return value" % (module.name, name))
            if longflag is not None and longflag in flags:
                raise SystemExit("%s: longflag %s twice" % (module.name, longflag))
            flags.add(longflag)
            found.append((p.tag, name, longflag, channel, p.findtext("default")))
    return found


def slicer_command(module, params, inputs, scratch):
    """The command line Slicer builds (vtkSlicerCLIModuleLogic): flags with values, booleans when true."""
    command, outputs, returns = [str(module)], [], []
    for tag, name, longflag, channel, default in params:
        if longflag is None:
            returns.append(name)
        elif channel == "output":
            path = scratch / (module.name + "_" + name + (".json" if tag == "file" else ".nrrd"))
            command += [longflag, str(path)]
            outputs.append(path)
        elif tag == "boolean":
            command.append(longflag)
        elif name in inputs:
            command += [longflag, str(inputs[name])]
        elif default:
            command += [longflag, default]
    if returns:
        command += ["--returnparameterfile", str(scratch / (module.name + ".params"))]
    return command, outputs, returns


def run_as_slicer(module, params, inputs, scratch):
    command, outputs, returns = slicer_command(module, params, inputs, scratch)
    run = subprocess.run(command, capture_output=True, text=True)
    if run.returncode != 0:
        raise SystemExit("%s failed (%d): %s\n%s" % (module.name, run.returncode, " ".join(command), run.stderr))
    tags = ["<filter-start>", "<filter-end>"] + (["<filter-progress>"] if module.name.endswith("Registration")
                                                  else [])
    for tag in tags:
        if tag not in run.stdout:
            raise SystemExit("%s: no %s on stdout" % (module.name, tag))
    for path in outputs:
        if not path.is_file() or path.stat().st_size == 0:
            raise SystemExit("%s: output %s not written" % (module.name, path.name))
    if returns:
        lines = (scratch / (module.name + ".params")).read_text().splitlines()
        named = {line.split("=", 1)[0].strip() for line in lines if "=" in line}
        if named != set(returns):
            raise SystemExit("%s: return values %s, expected %s" % (module.name, sorted(named), sorted(returns)))
    print("%s: %d parameters, %d outputs, %s" % (module.name, len(params), len(outputs),
                                                 "returns " + ", ".join(returns) if returns else "no return values"))


def rejects_unknown_flag(module):
    run = subprocess.run([str(module), "--noSuchFlag", "1"], capture_output=True, text=True)
    if run.returncode != 2 or len(run.stderr.strip().splitlines()) != 1:
        raise SystemExit("%s --noSuchFlag: exit %d, stderr %r" % (module.name, run.returncode, run.stderr))


def main(build, schema, scratch):
    build, schema, scratch = pathlib.Path(build), pathlib.Path(schema), pathlib.Path(scratch)
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    cli = build / "bin" / "biomechreg"
    pelvis = phantom(cli, scratch / "pelvis", "--scene", "pelvis", "--size", "100,80,40", "--spacing", "2,2,4",
                     "--truth-mesh-scale", "2", "--bladder-mm", "8", "--rectum-mm", "5")
    spheres = phantom(cli, scratch / "spheres", "--scene", "spheres", "--size", "64,64,64", "--spacing", "1,1,1")
    modules = sorted((build / "slicer").iterdir())
    if len(modules) != 4:
        raise SystemExit("expected 4 modules in %s, found %d" % (build / "slicer", len(modules)))
    for module in modules:
        xml = description(module)
        validate(module, xml, schema)
        run_as_slicer(module, parameters(module, xml), input_values(module, pelvis, spheres), scratch)
        rejects_unknown_flag(module)


if __name__ == "__main__":
    main(*sys.argv[1:])

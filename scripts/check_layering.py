#!/usr/bin/env python3
"""No include cycle between the library's stages (the folders of src/): run by ctest (layering_check).

A stage depends on another when one of its files (its sources, and the public headers it owns) includes a header
the other owns. A header in src/STAGE/ is
owned by STAGE; a public header in include/ by the stage whose folder holds the source of the same name
(include/itkFoo.h: src/*/itkFoo.cxx), else by OWNERS below. Prints the stages' dependencies, and for every cycle
the includes that make it; exits 1 on a cycle or on a public header no stage owns.

Usage: scripts/check_layering.py [REPOSITORY (default: this script's)]
"""
import os
import re
import sys
from collections import defaultdict

# Public headers without a source of their own name: declarations of several sources, templates, plain structs.
OWNERS = {
    "BiomechanicalRegistrationExport": "common",
    "bmrError": "common", "bmrGridGeometry": "common",
    "bmrNumerics": "common", "bmrTaskTrace": "common",
    "itkGridGeometryConversion": "common",
    "bmrTetrahedralMesh": "mesh", "bmrMesher": "mesh", "itkTetrahedralMeshObject": "mesh",
    "bmrLinearElasticModel": "fem", "bmrNeoHookeanForwardModel": "fem", "bmrForwardModel": "fem",
    # The label image meshed with the scene's sizes per label.
    "bmrScene": "scene", "bmrSimulation": "scene", "itkSceneDistanceMaps": "scene", "itkSliceInterpolation": "scene",
    "itkLabelImageToTetrahedralMeshFilter": "scene",
    "bmrDataTerm": "estimation", "bmrLoadParameterization": "estimation", "bmrEstimationObjective": "estimation",
    "bmrElasticityEstimator": "estimation", "bmrSurfaceMatchingObjective": "estimation",
    "bmrSignedDistanceSampler": "estimation", "bmrLandmarkTerm": "estimation", "bmrOrganSurfaceForces": "estimation",
    "bmrCompressionBarrier": "estimation", "itkFEMElasticityOptimizer": "estimation",
    "bmrDisplacementFieldRasterizer": "field", "itkPhysicsDeformationFieldSource": "field",
    "itkImageWarper": "field",
    "bmrLandmarks": "evaluation", "bmrStatistics": "evaluation", "bmrMarkerAlignment": "evaluation",
"itkRegistrationQualityMeasures": "evaluation",
    "itkLandmarkRegistrationError": "evaluation", "itkDemonsBaselineRegistrationFilter": "evaluation",
    "itkImplantedSeedDetection": "evaluation",
    "bmrDoseVolumeHistogram": "dose", "itkDoseEvaluation": "dose",
    # Image reading and writing that knows DICOM series and checks their structure.
    "itkDicomRT": "dicomrt", "itkDicomRTWriters": "dicomrt", "itkDicomStructureCheck": "dicomrt",
    "itkBiomechanicalImageIO": "dicomrt",
    "bmrAtomicFile": "io",
    "itkBiomechanicalReports": "output", "itkBiomechanicalWriters": "output",
    "bmrCohort": "cohort", "bmrCohortStudy": "cohort", "itkPhantomCohort": "cohort",
    "bmrPhantom": "synthetic",
    "itkBiomechanicalPipelines": "pipeline", "itkMarkerPipeline": "pipeline", "itkPipelineTypes": "pipeline",
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def stages_and_owners(root):
    src = os.path.join(root, "src")
    stages = sorted(d for d in os.listdir(src) if os.path.isdir(os.path.join(src, d)))
    owner, files = {}, defaultdict(list)
    for stage in stages:
        for name in os.listdir(os.path.join(src, stage)):
            base, ext = os.path.splitext(name)
            if ext in (".cxx", ".h", ".hxx"):
                owner.setdefault(base, stage)
                files[stage].append(os.path.join(src, stage, name))
    unowned = []
    for name in os.listdir(os.path.join(root, "include")):
        base = os.path.splitext(name)[0]
        if base not in owner:
            if base in OWNERS and OWNERS[base] in stages:
                owner[base] = OWNERS[base]
            else:
                unowned.append(name)
                continue
        # A public header's own includes are its stage's dependencies too.
        files[owner[base]].append(os.path.join(root, "include", name))
    return stages, owner, files, unowned


def dependencies(owner, files):
    edges, why = defaultdict(set), defaultdict(list)
    for stage, paths in files.items():
        for path in paths:
            with open(path, errors="replace") as f:
                for line in f:
                    m = INCLUDE.match(line)
                    if not m:
                        continue
                    target = owner.get(os.path.splitext(os.path.basename(m.group(1)))[0])
                    if target and target != stage:
                        edges[stage].add(target)
                        why[(stage, target)].append(f"{os.path.relpath(path)} includes {m.group(1)}")
    return edges, why


def cycles(stages, edges):
    """The strongly connected components of more than one stage (Tarjan)."""
    index, low, stack, on, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))
    for v in stages:
        if v not in index:
            visit(v)
    return found


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    os.chdir(root)
    stages, owner, files, unowned = stages_and_owners(".")
    edges, why = dependencies(owner, files)
    for stage in stages:
        print(f"{stage:11s} -> {', '.join(sorted(edges[stage])) or '(nothing)'}")
    ok = True
    for name in unowned:
        print(f"error: include/{name} belongs to no stage: add it to OWNERS in scripts/check_layering.py")
        ok = False
    for component in cycles(stages, edges):
        ok = False
        print("error: include cycle between " + ", ".join(component) + ":")
        for a in component:
            for b in component:
                for reason in why.get((a, b), [])[:3]:
                    print(f"  {a} -> {b}: {reason}")
    print("ok: no include cycle between the stages" if ok else "layering check failed")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

# Bad input to biomechreg: each case must exit non-zero with exactly one line on
# stderr, "biomechreg: error: ..." naming the cause, and leave no output file.
# Run with: cmake -DCLI=<biomechreg> -DTEMP=<dir> -P biomechregErrorTests.cmake
file(REMOVE_RECURSE ${TEMP})
file(MAKE_DIRECTORY ${TEMP})
set(failures 0)

function(expect_error name expected)
  execute_process(COMMAND ${CLI} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  string(STRIP "${err}" err_stripped)
  string(REGEX MATCHALL "\n" newlines "${err_stripped}")
  list(LENGTH newlines extra_lines)
  if(rc EQUAL 0)
    message(SEND_ERROR "${name}: exit code 0, expected an error")
  elseif(NOT err_stripped MATCHES "^biomechreg: error: ")
    message(SEND_ERROR "${name}: stderr does not start with 'biomechreg: error:': ${err}")
  elseif(extra_lines GREATER 0)
    message(SEND_ERROR "${name}: error message spans several lines: ${err}")
  elseif(out AND NOT out MATCHES "\n$")
    # A stage line ("  read inputs ...") left open would run into the error on a shared terminal.
    message(SEND_ERROR "${name}: stdout ends inside a line: ${out}")
  elseif(NOT err_stripped MATCHES "${expected}")
    message(SEND_ERROR "${name}: message does not mention '${expected}': ${err}")
  else()
    message(STATUS "ok ${name}: ${err_stripped}")
  endif()
endfunction()

# A small valid phantom to build the other cases from.
execute_process(COMMAND ${CLI} phantom --scene spheres --size 24,24,24 --spacing 4,4,4 --noise-HU 0 --out ${TEMP}/ok
  RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "could not make the reference phantom")
endif()
set(labels ${TEMP}/ok/moving_labels.nrrd)
file(READ ${TEMP}/ok/truth_scene.json scene)

expect_error(unknown_command "unknown command" frobnicate)
expect_error(unknown_option "unknown option --frob" phantom --out ${TEMP}/x --frob 1)
expect_error(missing_out "missing required option --out" phantom)
expect_error(bad_number "expects a number" phantom --out ${TEMP}/x --noise-HU abc)
expect_error(zero_spacing "spacing" phantom --out ${TEMP}/x --spacing 0,1,1)
expect_error(missing_file "cannot read moving label image" simulate --moving-labels ${TEMP}/none.nrrd
  --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s1)

file(WRITE ${TEMP}/corrupt.nrrd "NRRD0004\ntype: banana\ndimension: 3\n\n")
expect_error(corrupt_file "cannot read moving label image" simulate --moving-labels ${TEMP}/corrupt.nrrd
  --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s2)

file(WRITE ${TEMP}/flat.mha "ObjectType = Image\nNDims = 2\nDimSize = 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n0123456789abcdef")
expect_error(two_d_image "2-D; a 3-D image is required" simulate --moving-labels ${TEMP}/flat.mha
  --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s3)

file(WRITE ${TEMP}/truncated.mha "ObjectType = Image\nNDims = 3\nDimSize = 40 40 40\nElementType = MET_INT\nElementDataFile = LOCAL\n0123")
expect_error(truncated_file "cannot read moving label image" simulate --moving-labels ${TEMP}/truncated.mha
  --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s4)

# A mesh-quality threshold no tetrahedral mesh meets: refused, naming the element.
string(REPLACE "\"minimum_dihedral_angle_deg\": 0.1" "\"minimum_dihedral_angle_deg\": 69" bad "${scene}")
file(WRITE ${TEMP}/quality.json "${bad}")
expect_error(mesh_quality "element [0-9]+ \\(label .*dihedral angle of .* below mesh.minimum_dihedral_angle_deg"
  simulate --moving-labels ${labels} --scene ${TEMP}/quality.json --out ${TEMP}/s_quality)

string(REPLACE "\"poisson_ratio\": 0.35" "\"poisson_ratio\": 0.5" bad "${scene}")
file(WRITE ${TEMP}/nu.json "${bad}")
expect_error(poisson_half "labels\\[outer\\].poisson_ratio" simulate --moving-labels ${labels} --scene ${TEMP}/nu.json --out ${TEMP}/s5)

string(REPLACE "\"youngs_modulus_kPa\": 10" "\"youngs_modulus_kPa\": -10" bad "${scene}")
file(WRITE ${TEMP}/e.json "${bad}")
expect_error(negative_modulus "labels\\[outer\\].youngs_modulus_kPa" simulate --moving-labels ${labels} --scene ${TEMP}/e.json --out ${TEMP}/s6)

string(REPLACE "\"labels\"" "\"lables_typo\": 1, \"labels\"" bad "${scene}")
file(WRITE ${TEMP}/key.json "${bad}")
expect_error(unknown_key "lables_typo: unknown key" simulate --moving-labels ${labels} --scene ${TEMP}/key.json --out ${TEMP}/s7)

string(REPLACE "\"value\": 2" "\"value\": 7" bad "${scene}")
file(WRITE ${TEMP}/absent.json "${bad}")
expect_error(absent_label "contains label 2, which the scene does not describe" simulate --moving-labels ${labels}
  --scene ${TEMP}/absent.json --out ${TEMP}/s8)

string(JSON bad REMOVE "${scene}" loads)
file(WRITE ${TEMP}/rigid.json "${bad}")
expect_error(rigid_body "rigid-body motion" simulate --moving-labels ${labels} --scene ${TEMP}/rigid.json --out ${TEMP}/s9)

file(WRITE ${TEMP}/broken.json "{ \"labels\": [ ")
expect_error(broken_json "JSON" simulate --moving-labels ${labels} --scene ${TEMP}/broken.json --out ${TEMP}/s10)

expect_error(unwritable_output "cannot create output directory" simulate --moving-labels ${labels}
  --scene ${TEMP}/ok/truth_scene.json --out /proc/biomechreg-not-writable/out)

# register: an objective label missing from the fixed labels (the CT, cast to labels, has none of them),
# a fixed label image without any organ, a scene with nothing to estimate.
set(ok_register --moving-ct ${TEMP}/ok/moving_ct.nrrd --moving-labels ${labels} --fixed-ct ${TEMP}/ok/fixed_ct.nrrd)
expect_error(objective_label_missing "objective label \"inner\" \\(value 2\\) is missing from the fixed label image"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_ct.nrrd --scene ${TEMP}/ok/scene.json --out ${TEMP}/r1)
string(REPEAT "0 " 64 zeros)
file(WRITE ${TEMP}/empty_labels.nrrd "NRRD0004\ntype: int\ndimension: 3\nsizes: 4 4 4\nspacings: 4 4 4\nencoding: ascii\n\n${zeros}\n")
expect_error(empty_fixed_labels "is missing from the fixed label image"
  register ${ok_register} --fixed-labels ${TEMP}/empty_labels.nrrd --scene ${TEMP}/ok/scene.json --out ${TEMP}/r2)
string(JSON bad SET "${scene}" force_surfaces "[]")
file(WRITE ${TEMP}/nothing.json "${bad}")
expect_error(nothing_to_estimate "nothing to estimate"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/nothing.json --out ${TEMP}/r3)
expect_error(bad_step_limit "--element-inversion must be allow or limit"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --element-inversion sometimes --out ${TEMP}/r4)
expect_error(step_limit_reduced_basis "--element-inversion limit needs one parameter per wall node: --wall-spacing-mm 0"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --element-inversion limit --wall-spacing-mm 6 --out ${TEMP}/r5)
expect_error(pressure_with_spacing "--wall-spacing-mm does not apply to --wall-motion pressure"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --wall-motion pressure --wall-spacing-mm 6 --out ${TEMP}/r5)
expect_error(pressure_with_prior "--wall-regularization does not apply to --wall-motion pressure"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --wall-motion pressure --wall-regularization 0.01 --out ${TEMP}/r5)
expect_error(pressure_step_limit "a wall motion other than pressure"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --wall-motion pressure --element-inversion limit --out ${TEMP}/r5)
# Probability images: not ORGAN=FILE, an organ that is no objective organ, voxels outside [0, 1] (the fixed CT);
# a bad uncertainty method.
expect_error(probability_syntax "--fixed-probabilities takes ORGAN=FILE pairs"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --fixed-probabilities ${TEMP}/ok/fixed_ct.nrrd --out ${TEMP}/r6)
expect_error(probability_not_objective "\"bone\", which is not an objective organ"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --fixed-probabilities bone=${TEMP}/ok/fixed_ct.nrrd --out ${TEMP}/r7)
expect_error(probability_range "fixed probability of \"inner\": a voxel holds .*not a probability in \\[0, 1\\]"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --fixed-probabilities inner=${TEMP}/ok/fixed_ct.nrrd --out ${TEMP}/r8)
expect_error(bad_uncertainty "--uncertainty must be rescan, bootstrap, curvature or none"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --uncertainty guess --out ${TEMP}/r9)
# The advanced interval settings: an unknown name, a setting given both ways, a value its own option refuses.
expect_error(uncertainty_options_name "--uncertainty-options takes NAME=VALUE pairs .* got \"jitter=0.2\""
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --uncertainty-options jitter=0.2 --out ${TEMP}/r9)
expect_error(uncertainty_options_twice "--uncertainty-mesh-jitter is given twice"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --uncertainty-options mesh-jitter=0.2 --uncertainty-mesh-jitter 0.1 --out ${TEMP}/r9)
expect_error(uncertainty_options_value "--uncertainty-mesh-jitter must lie in \\[0, 0.9\\)"
  register ${ok_register} --fixed-labels ${TEMP}/ok/fixed_labels.nrrd --scene ${TEMP}/ok/scene.json
  --uncertainty-options shift-voxels=0.3,mesh-jitter=0.95 --out ${TEMP}/r9)

# Non-finite voxels, an absurd declared size, images that do not overlap in physical space.
string(REPEAT "40 " 63 values)
file(WRITE ${TEMP}/nan_ct.nrrd "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nspacings: 4 4 4\nencoding: ascii\n\n${values} nan\n")
expect_error(nan_voxel "moving CT .*voxel \\[3, 3, 3\\] is not finite" simulate --moving-labels ${labels}
  --moving-ct ${TEMP}/nan_ct.nrrd --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s11)
file(WRITE ${TEMP}/huge.mha "ObjectType = Image\nNDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_INT\nElementDataFile = LOCAL\n0000")
expect_error(huge_size "declares 1e\\+15 voxels \\(more than 2\\^31\\)" simulate --moving-labels ${TEMP}/huge.mha
  --scene ${TEMP}/ok/truth_scene.json --out ${TEMP}/s12)
file(WRITE ${TEMP}/far_labels.nrrd "NRRD0004\ntype: int\ndimension: 3\nsizes: 4 4 4\nspace: left-posterior-superior\n"
  "space origin: (10000,10000,10000)\nspace directions: (4,0,0) (0,4,0) (0,0,4)\nencoding: ascii\n\n${zeros}\n")
expect_error(no_overlap "the moving and fixed label images do not overlap in physical space"
  register ${ok_register} --fixed-labels ${TEMP}/far_labels.nrrd --scene ${TEMP}/ok/scene.json --out ${TEMP}/r4)

# A DICOM file (preamble, "DICM") without its File Meta Information: refused by the structure check before
# GDCM parses it (Debian's GDCM aborts on some such files), while the "read inputs" stage is open.
string(REPEAT "x" 128 preamble)
file(WRITE ${TEMP}/corrupt_dose.dcm "${preamble}DICMabcdefghijklmnop")
expect_error(corrupt_dicom_dose "dose image .*corrupt_dose.dcm\" is corrupt: no File Meta Information"
  dose --scene ${TEMP}/ok/scene.json --labels ${labels} --dose ${TEMP}/corrupt_dose.dcm --out ${TEMP}/s13)

# No partial outputs: none of the failed runs may have left a directory or temporary file.
foreach(dir s1 s2 s3 s4 s5 s6 s7 s8 s9 s10 s11 s12 s13 r1 r2 r3 r4 x)
  if(EXISTS ${TEMP}/${dir})
    file(GLOB leftovers ${TEMP}/${dir}/*)
    if(leftovers)
      message(SEND_ERROR "a failed run left files behind in ${TEMP}/${dir}: ${leftovers}")
    endif()
  endif()
endforeach()
file(GLOB_RECURSE temporaries ${TEMP}/.tmp-*)
if(temporaries)
  message(SEND_ERROR "temporary files left behind: ${temporaries}")
endif()

# demons, phantom-set and compare: usage errors and bad pair lists, refused before anything is written.
expect_error(demons_flatten_without_labels "--flatten needs --moving-labels and --fixed-labels"
  demons --moving-ct ${TEMP}/ok/moving_ct.nrrd --fixed-ct ${TEMP}/ok/fixed_ct.nrrd --flatten 2 --out ${TEMP}/d1)
expect_error(demons_bad_variant "--demons-variant must be diffeomorphic or symmetric"
  demons --moving-ct ${TEMP}/ok/moving_ct.nrrd --fixed-ct ${TEMP}/ok/fixed_ct.nrrd --demons-variant log --out ${TEMP}/d2)
expect_error(phantom_set_count "--count must be an integer in \\[1, 100\\]" phantom-set --count 0 --out ${TEMP}/p1)
expect_error(phantom_set_range "--bladder-range expects LOW,HIGH with 0.01 <= LOW <= HIGH <= 40, got \"15,8\""
  phantom-set --bladder-range 15,8 --out ${TEMP}/p1)
file(WRITE ${TEMP}/no_scene_column.csv "name,moving_ct,moving_labels,fixed_ct,fixed_labels\na,x,x,x,x\n")
expect_error(compare_missing_column "the header lacks the column \"scene\""
  compare --pairs ${TEMP}/no_scene_column.csv --out ${TEMP}/c1)
file(WRITE ${TEMP}/missing_file.csv "name,moving_ct,moving_labels,fixed_ct,fixed_labels,scene\n"
  "a,ok/moving_ct.nrrd,ok/moving_labels.nrrd,ok/nonexistent.nrrd,ok/fixed_labels.nrrd,ok/scene.json\n")
expect_error(compare_missing_file "fixed_ct \".*nonexistent.nrrd\" does not exist"
  compare --pairs ${TEMP}/missing_file.csv --out ${TEMP}/c2)
expect_error(compare_unknown_method "--methods takes identity, fem and demons"
  compare --pairs ${TEMP}/missing_file.csv --methods fem,elastix --out ${TEMP}/c3)
foreach(dir d1 d2 p1 c1 c2 c3)
  if(EXISTS ${TEMP}/${dir})
    message(SEND_ERROR "a refused run created ${TEMP}/${dir}")
  endif()
endforeach()

# Smoke test of stabint-run, one case per ctest entry (-DCASE=...): runs the executable ${RUN}
# and checks its exit status, its error line and the files it wrote under ${WORK}.
file(REMOVE_RECURSE "${WORK}/${CASE}")
file(MAKE_DIRECTORY "${WORK}/${CASE}")
set(dir "${WORK}/${CASE}")

function(expect_run expected_rc stderr_regex)
  execute_process(COMMAND "${RUN}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc STREQUAL "${expected_rc}")
    message(FATAL_ERROR "stabint-run ${ARGN}\nexit status ${rc}, expected ${expected_rc}\nstdout:\n${out}\nstderr:\n${err}")
  endif()
  if(NOT err MATCHES "${stderr_regex}")
    message(FATAL_ERROR "stabint-run ${ARGN}\nstderr does not match '${stderr_regex}':\n${err}")
  endif()
  set(run_stdout "${out}" PARENT_SCOPE)
endfunction()

function(expect_csv_rows file rows)
  file(STRINGS "${file}" lines)
  list(LENGTH lines n)
  math(EXPR want "${rows} + 1")
  if(NOT n EQUAL want)
    message(FATAL_ERROR "${file}: ${n} lines, expected ${want} (header + ${rows} frames)")
  endif()
  list(GET lines 0 header)
  if(NOT header STREQUAL "frame,time,kinetic,elastic,external,total,target,forcing,damping,event_energy,friction,contact_projection,branch,alpha,velocity_scale,iterations,energy_evaluations,local_s,gather_s,transfer_s,global_s,energy_s,bookkeeping_s")
    message(FATAL_ERROR "${file}: unexpected header '${header}'")
  endif()
endfunction()

if(CASE STREQUAL "chain_csv")
  expect_run(0 "10 frames in" --scene chain --param particles=8 --backend cpu --integrator blend
             --frames 10 --csv "${dir}/chain.csv" --obj-dir "${dir}/obj")
  expect_csv_rows("${dir}/chain.csv" 11)
  file(STRINGS "${dir}/chain.csv" lines)
  list(GET lines 11 last)
  if(NOT last MATCHES "^10,0\\.333")
    message(FATAL_ERROR "last CSV row should be frame 10 at t = 1/3: '${last}'")
  endif()
  file(GLOB objs "${dir}/obj/*.obj")
  list(LENGTH objs n)
  if(NOT n EQUAL 11)
    message(FATAL_ERROR "expected 11 OBJ frames, got ${n}")
  endif()
  file(STRINGS "${dir}/obj/frame_00010.obj" v REGEX "^v ")
  file(STRINGS "${dir}/obj/frame_00010.obj" l REGEX "^l ")
  list(LENGTH v nv)
  list(LENGTH l nl)
  if(NOT nv EQUAL 8 OR NOT nl EQUAL 7)
    message(FATAL_ERROR "frame_00010.obj: ${nv} vertices and ${nl} lines, expected 8 and 7")
  endif()
elseif(CASE STREQUAL "scene_files")
  foreach(scene chain cloth_handle tetbar cloth_wind cloth_triangles cloth_poke)
    expect_run(0 "3 frames in" --scene "${SCENES}/${scene}.json" --backend cpu --frames 3 --every 2 --csv -)
    string(REGEX MATCHALL "\n[0-9]+," rows "\n${run_stdout}")
    list(LENGTH rows n)
    if(NOT n EQUAL 3)  # frames 0, 2 and the last one, 3
      message(FATAL_ERROR "${scene}.json: expected 3 CSV rows on stdout, got ${n}:\n${run_stdout}")
    endif()
  endforeach()
elseif(CASE STREQUAL "events")
  # scenes/cloth_drag.json replays its scripted events (the grab at frame 30 first): its energies
  # equal those of the same cloth without events up to frame 30 and differ from frame 31 on.
  expect_run(0 "4 scripted events" --scene "${SCENES}/cloth_drag.json" --backend cpu --frames 40 --csv "${dir}/drag.csv")
  expect_csv_rows("${dir}/drag.csv" 41)
  file(WRITE "${dir}/plain.json"
       "{\"format\": \"stabint-scene\", \"version\": 1, \"builtin\": {\"name\": \"cloth\", \"nx\": 20, \"ny\": 20}}")
  expect_run(0 "40 frames in" --scene "${dir}/plain.json" --backend cpu --frames 40 --csv "${dir}/plain.csv")
  file(STRINGS "${dir}/drag.csv" drag)
  file(STRINGS "${dir}/plain.csv" plain)
  foreach(row 31 32)  # frames 30 and 31 (row 0 is the header)
    list(GET drag ${row} d)
    list(GET plain ${row} p)
    # frame, time and the energies: the columns before the timings.
    set(columns "^[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,")  # CMake's regex has no {7}
    string(REGEX MATCH "${columns}" d "${d}")
    string(REGEX MATCH "${columns}" p "${p}")
    if(d STREQUAL "" OR p STREQUAL "")
      message(FATAL_ERROR "row ${row}: no CSV columns found")
    endif()
    if(row EQUAL 31 AND NOT d STREQUAL p)
      message(FATAL_ERROR "frame 30 should be untouched by the events:\n${d}\n${p}")
    elseif(row EQUAL 32 AND d STREQUAL p)
      message(FATAL_ERROR "frame 31 should follow the grab:\n${d}")
    endif()
  endforeach()
  # scenes/cloth_poke.json replays its collider events: the sphere reaches the cloth near frame 40
  # and its work shows in the CSV's forcing column (the eighth), zero before.
  expect_run(0 "2 scripted events" --scene "${SCENES}/cloth_poke.json" --backend cpu --frames 60 --csv "${dir}/poke.csv")
  expect_csv_rows("${dir}/poke.csv" 61)
  file(STRINGS "${dir}/poke.csv" poke)
  set(forced 0)
  foreach(line ${poke})
    if(line MATCHES "^[0-9]+,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,([^,]*),")
      if(NOT CMAKE_MATCH_1 STREQUAL "0")
        set(forced 1)
      endif()
    endif()
  endforeach()
  if(NOT forced)
    message(FATAL_ERROR "cloth_poke.json: no forcing booked in 60 frames")
  endif()
  # A bad event is an error naming its JSON path.
  file(WRITE "${dir}/bad.json"
       "{\"format\": \"stabint-scene\", \"builtin\": {\"name\": \"cloth\", \"nx\": 4, \"ny\": 4}, "
       "\"events\": [{\"frame\": 2, \"grab\": {\"vertex\": 16, \"stiffness\": 1e3}}]}")
  expect_run(1 "bad.json: events\\[0\\]\\.grab\\.vertex: particle index 16 out of range" --scene "${dir}/bad.json" --frames 3)
elseif(CASE STREQUAL "triangle_cloth")
  # The cloth grid built from triangle strain and bending hinges; its OBJ frames carry the
  # grid's faces (Scene::triangles).
  expect_run(0 "40 triangle strains, 51 bending hinges, 2 pins.*3 frames in" --scene cloth --param model=triangles
             --param nx=6 --param ny=5 --backend cpu --frames 3 --obj-dir "${dir}/obj")
  file(STRINGS "${dir}/obj/frame_00003.obj" v REGEX "^v ")
  file(STRINGS "${dir}/obj/frame_00003.obj" f REGEX "^f ")
  list(LENGTH v nv)
  list(LENGTH f nf)
  if(NOT nv EQUAL 30 OR NOT nf EQUAL 40)
    message(FATAL_ERROR "frame_00003.obj: ${nv} vertices and ${nf} faces, expected 30 and 40")
  endif()
elseif(CASE STREQUAL "blow_up")
  # Forward Euler on the stiff chain at 30 Hz diverges within a few dozen steps.
  expect_run(2 "stabint-run: error: the state became non-finite at frame [0-9]+" --scene chain --backend cpu
             --integrator FE --frames 2000 --csv "${dir}/fe.csv")
  file(STRINGS "${dir}/fe.csv" lines)
  list(LENGTH lines n)
  if(n LESS 2)
    message(FATAL_ERROR "the CSV should keep the frames before the blow-up")
  endif()
  # The same run with an energy ceiling stops at once, the same way. Frames count from 1 (frame 0
  # is the initial state) and the library's message labels its step as an index from 0: frame 2
  # is the step from t = 1/30 to 2/30, step index 1.
  expect_run(2 "stabint-run: error: the energy limit was exceeded at frame 2 \\(t = 0\\.0666667 s\\); step index 1 \\(t = 0\\.0333333 -> 0\\.0666667, integrator FE\\): .*exceeds the target H"
             --scene chain --backend cpu --integrator FE --frames 2000 --energy-limit 10 --quiet)
elseif(CASE STREQUAL "opencl_fallback")
  # An empty ICD vendor directory: the loader finds no platform. The default backend (auto) runs
  # on the CPU reference and says why; an explicit --backend opencl fails.
  file(MAKE_DIRECTORY "${dir}/no_vendors")
  set(ENV{OCL_ICD_VENDORS} "${dir}/no_vendors")
  expect_run(0 "on CPU reference \\(double\\) \\[auto: no OpenCL device" --scene oscillator --frames 2)
  expect_run(1 "^stabint-run: error: .*no OpenCL platform" --scene oscillator --frames 2 --backend opencl)
elseif(CASE STREQUAL "bad_option")
  expect_run(1 "^stabint-run: error: unknown option '--no-such-option'" --scene chain --no-such-option)
elseif(CASE STREQUAL "bad_value")
  expect_run(1 "^stabint-run: error: --dt: expected a number, got 'fast'" --scene chain --dt fast)
elseif(CASE STREQUAL "bad_arguments")
  # Each mistake is named: an option given twice (a second value would silently win), an option
  # whose value is missing (the next option is not taken as its value), a number strtod reads but
  # no user means (hexadecimal), an output directory that is a file.
  expect_run(1 "^stabint-run: error: --scene: given twice" --scene chain --scene cloth --frames 1)
  expect_run(1 "^stabint-run: error: --time-step: given twice \\(--dt is --time-step\\)" --scene chain --dt 0.01
             --time-step 0.02)
  expect_run(1 "^stabint-run: error: --frames: missing value \\(the next argument is the option '--quiet'\\)"
             --scene chain --frames --quiet)
  expect_run(1 "^stabint-run: error: --dt: expected a number, got '0x10'" --scene chain --dt 0x10)
  expect_run(1 "^stabint-run: error: --frames: expected an integer, got ' 3'" --scene chain --frames " 3")
  expect_run(1 "^stabint-run: error: --frames: 2147483648 is out of range \\(-2147483648 to 2147483647\\)" --scene chain
             --frames 2147483648)
  expect_run(1 "^stabint-run: error: --frames: 99999999999999999999999 is out of range" --scene chain
             --frames 99999999999999999999999)
  file(WRITE "${dir}/a_file" "")
  expect_run(1 "^stabint-run: error: --obj-dir: cannot make the directory '${dir}/a_file'" --scene chain --backend cpu
             --frames 1 --quiet --obj-dir "${dir}/a_file")
  expect_run(1 "^stabint-run: error: --vtk: cannot make the directory '${dir}/a_file/frames'" --scene chain
             --backend cpu --frames 1 --quiet --vtk "${dir}/a_file/frames")
  # Decimal forms are all numbers.
  expect_run(0 "" --scene chain --backend cpu --frames 1 --quiet --dt .5e-2)
elseif(CASE STREQUAL "bad_integrator")
  expect_run(1 "^stabint-run: error: --integrator: unknown integrator 'RK4'" --scene chain --integrator RK4)
elseif(CASE STREQUAL "bad_param")
  expect_run(1 "params: unknown field 'nope'" --scene chain --param nope=1)
elseif(CASE STREQUAL "missing_scene_file")
  expect_run(1 "^stabint-run: error: ${WORK}/missing.json: cannot open file" --scene "${WORK}/missing.json")
elseif(CASE STREQUAL "output_full")
  # A full disk is an error, not a silent success with nothing written.
  expect_run(1 "^stabint-run: error: --csv: /dev/full: write failed" --scene chain --backend cpu --frames 3 --quiet
             --csv /dev/full)
  execute_process(COMMAND "${RUN}" --scene chain --backend cpu --frames 3 --quiet --csv - OUTPUT_FILE /dev/full
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "^stabint-run: error: --csv: standard output: write failed")
    message(FATAL_ERROR "--csv - into /dev/full: exit status ${rc} (expected 1), stderr:\n${err}")
  endif()
elseif(CASE STREQUAL "param_splice")
  # A --param value is one JSON value: it cannot smuggle in further keys.
  expect_run(1 "^stabint-run: error: --param pinned: expected a number, a \\[list\\] or a word"
             --scene cloth --backend cpu --frames 1 --param "pinned=[0], \"nx\": 3")
  expect_run(1 "^stabint-run: error: --param nx: given twice" --scene cloth --backend cpu --frames 1
             --param nx=3 --param nx=4)
elseif(CASE STREQUAL "sigterm" OR CASE STREQUAL "sigint")
  # SIGTERM (or SIGINT, Ctrl-C) in the middle of a long run: the CSV keeps every frame up to the
  # one reported. The run is signalled once its frame loop has written rows (so the handler is
  # installed), whenever that is on this machine; the CSV buffer then holds rows that only the
  # handler saves. (A background job of sh starts with SIGINT ignored; the handler replaces that.)
  if(CASE STREQUAL "sigterm")
    set(signal TERM)
    set(status 143)
  else()
    set(signal INT)
    set(status 130)
  endif()
  execute_process(COMMAND sh -c "
    \"$0\" --scene chain --backend cpu --frames 1000000000 --csv \"$1/sig.csv\" --quiet 2> \"$1/err.txt\" &
    pid=$!
    while kill -0 $pid 2>/dev/null && [ \"$(wc -l < \"$1/sig.csv\" 2>/dev/null || echo 0)\" -lt 2 ]; do sleep 0.05; done
    kill -$2 $pid
    wait $pid
    echo $? > \"$1/rc.txt\"" "${RUN}" "${dir}" "${signal}")
  file(READ "${dir}/rc.txt" rc)
  file(READ "${dir}/err.txt" err)
  string(STRIP "${rc}" rc)
  if(NOT rc STREQUAL "${status}" OR NOT err MATCHES "^stabint-run: interrupted by SIG${signal} after frame ([0-9]+); CSV kept up to frame ([0-9]+)\n$")
    message(FATAL_ERROR "SIG${signal}: exit status ${rc} (expected ${status}), stderr:\n${err}")
  endif()
  set(frame "${CMAKE_MATCH_1}")
  file(STRINGS "${dir}/sig.csv" lines)
  list(LENGTH lines n)
  list(GET lines -1 last)
  math(EXPR want "${frame} + 2")
  if(NOT n EQUAL want OR NOT last MATCHES "^${frame},")
    message(FATAL_ERROR "SIG${signal} after frame ${frame}: the CSV has ${n} lines (expected ${want}), last '${last}'")
  endif()
elseif(CASE STREQUAL "help")
  expect_run(0 "" --help)
  if(NOT run_stdout MATCHES "Usage: stabint-run --scene")
    message(FATAL_ERROR "--help prints no usage:\n${run_stdout}")
  endif()
  # -h is --help, alone or among other options (which it ends, as --help does).
  set(help "${run_stdout}")
  foreach(args "-h" "--scene;chain;-h")
    expect_run(0 "" ${args})
    if(NOT run_stdout STREQUAL help)
      message(FATAL_ERROR "stabint-run ${args} prints something else than --help:\n${run_stdout}")
    endif()
  endforeach()
  expect_run(1 "^stabint-run: error: unexpected argument '-x'" --scene chain -x)
elseif(CASE STREQUAL "version")
  # The project's version (CMakeLists.txt), alone on standard output; no --scene needed.
  file(STRINGS "${SCENES}/../CMakeLists.txt" project REGEX "^project\\(stabint VERSION ")
  string(REGEX REPLACE ".*VERSION ([0-9.]+).*" "\\1" version "${project}")
  expect_run(0 "^$" --version)
  if(NOT run_stdout STREQUAL "stabint-run ${version}\n")
    message(FATAL_ERROR "--version printed '${run_stdout}', expected 'stabint-run ${version}'")
  endif()
  expect_run(1 "^stabint-run: error: --version: takes no value" --version=2)
elseif(CASE STREQUAL "mesh_scenes")
  # A mesh file is a scene: each format the library's loaders read, by its extension (any case),
  # TetGen by either of its two files.
  file(COPY_FILE "${SCENES}/bar.mesh" "${dir}/BAR.MESH")
  foreach(mesh "cloth_square.obj;121 particles" "bar.mesh;20 particles, 24 tets" "bar.node;20 particles, 24 tets"
               "bar.ele;20 particles, 24 tets" "${dir}/BAR.MESH;20 particles, 24 tets")
    list(GET mesh 0 file)
    list(GET mesh 1 summary)
    if(NOT IS_ABSOLUTE "${file}")
      set(file "${SCENES}/${file}")
    endif()
    expect_run(0 "scene '[A-Za-z_]+' \\(${summary}" --scene "${file}" --backend cpu --frames 3 --csv -)
    string(REGEX MATCHALL "\n[0-9]+," rows "\n${run_stdout}")
    list(LENGTH rows n)
    if(NOT n EQUAL 4)
      message(FATAL_ERROR "${file}: expected 4 CSV rows, got ${n}:\n${run_stdout}")
    endif()
  endforeach()
  # A mesh's own errors are the loader's (file and line), not a JSON parser's.
  file(WRITE "${dir}/broken.obj" "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
  expect_run(1 "^stabint-run: error: ${dir}/broken.obj:4: .*out of range" --scene "${dir}/broken.obj")
  expect_run(1 "^stabint-run: error: ${dir}/missing.obj: cannot open" --scene "${dir}/missing.obj")
  # Gmsh is not among them: the error says so and how to convert, whether or not the file exists.
  expect_run(1 "^stabint-run: error: --scene: '${dir}/part.msh': Gmsh .msh files are not read by the library's loaders.*meshio convert"
             --scene "${dir}/part.msh")
  expect_run(1 "^stabint-run: error: --param applies to built-in scenes only" --scene "${SCENES}/bar.mesh" --param nx=3)
elseif(CASE STREQUAL "mesh_ground")
  # A mesh lands on the ground plane the CLI adds, a quarter of its bounding-box diagonal below its
  # lowest point: the bar (1 x 0.25 x 0.25 m, lowest at y = 0, diagonal 1.0607 m) falls onto
  # y = -0.265 and rests there after 2 s (20 m below its start without the plane).
  expect_run(0 "" --scene "${SCENES}/bar.mesh" --backend cpu --frames 60 --every 60 --quiet --obj-dir "${dir}/obj")
  file(STRINGS "${dir}/obj/frame_00060.obj" vertices REGEX "^v ")
  set(lowest 1e30)
  foreach(v ${vertices})
    string(REGEX REPLACE "^v [^ ]+ ([^ ]+) .*" "\\1" y "${v}")
    if(y LESS lowest)
      set(lowest "${y}")
    endif()
  endforeach()
  if(lowest LESS -0.29 OR lowest GREATER -0.24)
    message(FATAL_ERROR "the bar's lowest point after 2 s is at y = ${lowest}, expected on the ground at -0.265")
  endif()
elseif(CASE STREQUAL "option_flags")
  # Every row of the options' table (include/stabint/options_table.h) has its flag, the
  # field name with '-' for '_', in --help; the nested OpenCL options have --platform, --device
  # and --precision.
  expect_run(0 "" --help)
  file(READ "${SCENES}/../include/stabint/options_table.h" header)
  string(FIND "${header}" "#define STABINT_SIMULATOR_OPTIONS_TABLE" begin)
  string(FIND "${header}" "#define STABINT_OPENCL_OPTIONS_TABLE" end)
  math(EXPR length "${end} - ${begin}")
  string(SUBSTRING "${header}" ${begin} ${length} list)
  string(REGEX MATCHALL "\n +FIELD\\(T\\([A-Za-z]+\\), [a-z_]+," entries "${list}")
  list(LENGTH entries n)
  if(n LESS 20)
    message(FATAL_ERROR "found ${n} FIELD rows in options_table.h, expected at least 20")
  endif()
  foreach(entry ${entries} "x, platform," "x, device," "x, precision,")
    string(REGEX REPLACE ".*, ([a-z_]+),$" "\\1" field "${entry}")
    string(REPLACE "_" "-" flag "--${field}")
    if(NOT run_stdout MATCHES "\n  ${flag} ")
      message(FATAL_ERROR "--help lists no ${flag}:\n${run_stdout}")
    endif()
  endforeach()
  # The flags reach the simulator: time and iterations in the CSV, --dt as --time-step ...
  foreach(step_flag --time-step --dt)
    expect_run(0 "" --scene chain --backend cpu --frames 2 --quiet --integrator BE --acceleration none
               ${step_flag} 0.01 --iterations 3 --csv -)
    string(REGEX MATCH "\n2,0\\.02,[^\n]*" row "${run_stdout}")
    string(REPLACE "," ";" columns "${row}")
    list(GET columns 15 iterations)
    if(NOT iterations STREQUAL "3")
      message(FATAL_ERROR "${step_flag} 0.01 --iterations 3: frame 2 is '${row}'")
    endif()
  endforeach()
  # ... and the simulator's checks see the new flags' values.
  expect_run(1 "lbfgs_history = 51 must be in" --scene chain --backend cpu --frames 1 --lbfgs-history 51)
  expect_run(1 "energy_tolerance = 0 must be finite and > 0" --scene chain --backend cpu --frames 1 --energy-tolerance=0)
  expect_run(1 "cg_iterations = 0 must be >= 1" --scene chain --backend cpu --frames 1 --global-solve cg
             --cg-iterations 0)
  expect_run(1 "^stabint-run: error: --global-solve: unknown global solve 'lu'" --scene chain --global-solve lu)
  expect_run(1 "^stabint-run: error: --max-iterations: expected an integer, got '1.5'" --scene chain
             --max-iterations 1.5)
else()
  message(FATAL_ERROR "unknown CASE '${CASE}'")
endif()

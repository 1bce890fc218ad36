"""Build the ``simulation_interfaces`` ROS 2 package (Python + C type supports) for an
environment made of the ``ros-jazzy-*`` wheels from PyPI, without CMake, colcon or a ROS install.

Why: the stock-ROS tests (``tests/ros2/test_rclpy_services.py``) run a real Jazzy rclpy client
on Fast DDS (``rmw_fastrtps_cpp``) that calls ``/get_simulation_state``, but PyPI has no
``ros-jazzy-simulation-interfaces`` wheel. The rosidl generators *are* wheels there (and come
with rclpy), so this script does what ``rosidl_generate_interfaces()`` does in a colcon build,
from the ``.msg``/``.srv``/``.action`` files marsscene ships
(``marsscene/ros2/interfaces/simulation_interfaces``):

1. rosidl_adapter: ``.msg``/``.srv``/``.action`` -> ``.idl``;
2. rosidl_generator_type_description: ``.idl`` -> ``.json`` (type descriptions, RIHS01 hashes);
3. rosidl_generator_c, rosidl_typesupport_introspection_c, rosidl_typesupport_fastrtps_c,
   rosidl_typesupport_c (the dispatcher) and rosidl_generator_py: the generated sources;
4. gcc/g++: ``lib<pkg>__<generator>.so`` against the headers and libraries the wheels put in the
   venv (``<prefix>/include/<pkg>``, ``<prefix>/lib``; dependencies such as geometry_msgs,
   std_msgs, service_msgs, action_msgs and unique_identifier_msgs are reused from there), and the
   ``<pkg>_s__<typesupport>`` Python extension modules rclpy imports.

The generators run under the ROS environment's Python (the script re-runs itself there).
Output: ``OUT/simulation_interfaces`` (the Python package) and ``LIBDIR`` (default ``OUT/lib``).
Use it with ``PYTHONPATH=OUT`` and ``LD_LIBRARY_PATH=LIBDIR`` (rosidl_typesupport_c looks the
Fast DDS type support library up on ``LD_LIBRARY_PATH``); or install it into the venv, like a
wheel would, with ``--out <venv site-packages> --libdir <venv>/lib``.

    python tools/ros_interfaces.py --ros-python /tmp/ros/bin/python --out DIR
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "marsscene/ros2/interfaces/simulation_interfaces"
# packages rosidl_generate_interfaces() adds on its own: services carry a service_msgs event
# type, actions are built of action_msgs, unique_identifier_msgs and builtin_interfaces types
IMPLICIT = {".srv": {"service_msgs"},
            ".action": {"action_msgs", "unique_identifier_msgs", "builtin_interfaces",
                        "service_msgs"}}


def interface_files(src: Path) -> list[Path]:
    """The package's definitions, relative to ``src`` (msg/…, srv/…, action/…)."""
    return sorted(p.relative_to(src) for sub in ("msg", "srv", "action")
                  for p in (src / sub).glob("*.*") if p.suffix == "." + sub)


def dependencies(src: Path, files: list[Path], pkg: str) -> list[str]:
    """Packages named by field types (``geometry_msgs/Pose[] poses``) plus the implicit ones."""
    deps: set[str] = set()
    for rel in files:
        deps |= IMPLICIT.get(rel.suffix, set())
        for line in (src / rel).read_text(encoding="utf-8").splitlines():
            m = re.match(r"\s*([a-z][a-z0-9_]*)/[A-Z]\w*", line)
            deps |= {m.group(1)} if m else set()
    return sorted(deps - {pkg})


def run_generators(pkg: str, src: Path, files: list[Path], deps: list[str], prefix: Path,
                   gen: Path) -> list[str]:
    """Steps 1-3 under the ROS Python; returns the C type supports the dispatcher serves."""
    from rosidl_adapter import convert_to_idl
    from rosidl_generator_c import generate_c
    from rosidl_generator_py import generate_py
    from rosidl_generator_type_description import generate_type_hash
    from rosidl_typesupport_c import generate_c as generate_dispatch_c
    from rosidl_typesupport_fastrtps_c import generate_typesupport_fastrtps_c
    from rosidl_typesupport_introspection_c import generate_c as generate_introspection_c

    share = prefix / "share"
    idl_dir = gen / "idl"
    with contextlib.redirect_stdout(io.StringIO()):  # the adapter prints a line per file
        idls = [convert_to_idl(src, pkg, rel, idl_dir).relative_to(idl_dir) for rel in files]
    dep_idls = [f"{d}:{p}" for d in deps for p in sorted((share / d).glob("*/*.idl"))]
    common = {"package_name": pkg, "idl_tuples": [f"{idl_dir}:{i.as_posix()}" for i in idls],
              "ros_interface_dependencies": dep_idls, "target_dependencies": []}

    def args_file(name: str, template_pkg: str, **extra) -> str:
        out = gen / name / pkg
        out.mkdir(parents=True, exist_ok=True)
        path = gen / f"{name}__arguments.json"
        path.write_text(json.dumps({**common, "output_dir": str(out),
                                    "template_dir": str(share / template_pkg / "resource"),
                                    **extra}))
        return str(path)

    def visibility(name: str) -> None:  # CMake's configure_file() of the *.h.in template
        text = (share / name / "resource" / f"{name}__visibility_control.h.in").read_text()
        text = text.replace("@PROJECT_NAME@", pkg).replace("@PROJECT_NAME_UPPER@", pkg.upper())
        (gen / name / pkg / "msg").mkdir(parents=True, exist_ok=True)
        (gen / name / pkg / "msg" / f"{name}__visibility_control.h").write_text(text)

    type_desc = args_file("rosidl_generator_type_description", "rosidl_generator_type_description",
                          include_paths=[f"{d}:{share / d}" for d in deps])
    # keyed "msg/Foo": msg/SpawnEntity and srv/SpawnEntity share a name
    jsons = {f"{Path(j).parent.name}/{Path(j).stem}": j for j in generate_type_hash(type_desc)}
    tuples = [f"{i.as_posix()}:{jsons[i.with_suffix('').as_posix()]}" for i in idls]
    generate_c(args_file("rosidl_generator_c", "rosidl_generator_c",
                         type_description_tuples=tuples,
                         ros_interface_files=[str(src / rel) for rel in files]))
    visibility("rosidl_generator_c")
    generate_introspection_c(args_file("rosidl_typesupport_introspection_c",
                                       "rosidl_typesupport_introspection_c"))
    visibility("rosidl_typesupport_introspection_c")
    generate_typesupport_fastrtps_c(args_file("rosidl_typesupport_fastrtps_c",
                                              "rosidl_typesupport_fastrtps_c"))
    visibility("rosidl_typesupport_fastrtps_c")
    # CMake's get_used_typesupports(): the C type supports registered in the ament index
    supports = sorted(p.name for p in (
        share / "ament_index/resource_index/rosidl_typesupport_c").iterdir())
    if "rosidl_typesupport_fastrtps_c" not in supports:
        raise SystemExit("rosidl_typesupport_fastrtps_c is not installed (rmw_fastrtps_cpp "
                         "needs it)")
    generate_dispatch_c(args_file("rosidl_typesupport_c", "rosidl_typesupport_c"), supports)
    generate_py(args_file("rosidl_generator_py", "rosidl_generator_py"),
                ["rosidl_typesupport_c", *supports])
    return supports


def compile_all(pkg: str, deps: list[str], prefix: Path, gen: Path, out: Path, libdir: Path,
                supports: list[str], jobs: int) -> None:
    """Step 4: what the CMake targets of rosidl_generate_interfaces() compile and link."""
    import numpy

    includes = [f"-I{p}" for p in [prefix / "include", *sorted((prefix / "include").iterdir())]
                if p.is_dir()]
    py_inc = [f"-I{sysconfig.get_paths()['include']}", f"-I{numpy.get_include()}"]
    rpath = f"-Wl,-rpath,{prefix / 'lib'}"
    objs = gen / "obj"

    def own(*suffixes: str) -> list[str]:
        return [f"-l{pkg}__{s}" for s in suffixes]

    def of_deps(suffix: str) -> list[str]:
        return [f"-l{d}__{suffix}" for d in deps]

    # lib<pkg>__<name>.so: (its sources in gen/<name>/<pkg>, extra includes, libraries,
    # DEFINE_SYMBOL), in dependency order (rosidl_generator_c first)
    targets = {
        "rosidl_generator_c": (
            "*/detail/*.c", [],
            [*of_deps("rosidl_generator_c"), "-lrosidl_runtime_c", "-lrcutils"],
            "ROSIDL_GENERATOR_C_BUILDING_DLL"),
        "rosidl_typesupport_introspection_c": (
            "*/detail/*.c", [],
            [*own("rosidl_generator_c"), *of_deps("rosidl_typesupport_introspection_c"),
             "-lrosidl_typesupport_introspection_c", "-lrosidl_runtime_c"],
            "ROSIDL_TYPESUPPORT_INTROSPECTION_C_BUILDING_DLL"),
        "rosidl_typesupport_fastrtps_c": (
            "*/detail/*.cpp", [],
            [*own("rosidl_generator_c"), *of_deps("rosidl_typesupport_fastrtps_c"),
             *of_deps("rosidl_generator_c"), "-lrosidl_typesupport_fastrtps_c",
             "-lrosidl_typesupport_fastrtps_cpp", "-lfastcdr", "-lrosidl_runtime_c",
             "-lrcutils"],
            "ROSIDL_TYPESUPPORT_FASTRTPS_C_BUILDING_DLL"),
        "rosidl_typesupport_c": (
            "*/*.cpp", [],
            [*own("rosidl_generator_c"), *of_deps("rosidl_typesupport_c"),
             "-lrosidl_typesupport_c", "-lrosidl_runtime_c"],
            "ROSIDL_GENERATOR_C_BUILDING_DLL"),
        "rosidl_generator_py": (
            "*/_*_s.c", py_inc,
            [*own("rosidl_generator_c", "rosidl_typesupport_c"),
             *of_deps("rosidl_generator_py"), *of_deps("rosidl_generator_c"),
             "-lrosidl_runtime_c", "-lrcutils"],
            ""),
    }
    gen_inc = [f"-I{gen / d}" for d in ("rosidl_generator_c", "rosidl_generator_py",
                                        "rosidl_typesupport_introspection_c",
                                        "rosidl_typesupport_fastrtps_c")]

    def cc(source: Path, extra: list[str], define: str) -> Path:
        obj = objs / source.relative_to(gen).with_suffix(".o")
        obj.parent.mkdir(parents=True, exist_ok=True)
        std = ["g++", "-std=c++17"] if source.suffix == ".cpp" else ["gcc", "-std=c11"]
        defs = [f"-D{define}_{pkg}"] if define else []
        cmd = [*std, "-c", "-O2", "-fPIC", *defs, *gen_inc, *extra, *includes, str(source),
               "-o", str(obj)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode:
            raise SystemExit(f"compile failed: {' '.join(cmd)}\n{done.stderr}")
        return obj

    def link(objects: list[Path], target: Path, libs: list[str], origin_rel: str) -> None:
        cmd = ["g++", "-shared", "-o", str(target), *map(str, objects),
               f"-L{libdir}", f"-L{prefix / 'lib'}", f"-Wl,-rpath,$ORIGIN/{origin_rel}", rpath,
               *libs]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode:
            raise SystemExit(f"link failed: {' '.join(cmd)}\n{done.stderr}")

    libdir.mkdir(parents=True, exist_ok=True)
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        jobs_of = {name: [pool.submit(cc, s, extra, define)
                          for s in sorted((gen / name / pkg).glob(pattern))]
                   for name, (pattern, extra, _, define) in targets.items()}
        eps = {ts: pool.submit(cc, gen / "rosidl_generator_py" / pkg /
                               f"_{pkg}_s.ep.{ts}.c", py_inc, "")
               for ts in ["rosidl_typesupport_c", *supports]}
        for name, futures in jobs_of.items():
            link([f.result() for f in futures], libdir / f"lib{pkg}__{name}.so",
                 targets[name][2], ".")
        # the package: the generated .py files, then one extension module per type support
        pkg_out = out / pkg
        if pkg_out.exists():
            shutil.rmtree(pkg_out)
        shutil.copytree(gen / "rosidl_generator_py" / pkg, pkg_out,
                        ignore=shutil.ignore_patterns("*.c"))
        ext = sysconfig.get_config_var("EXT_SUFFIX")
        rel = os.path.relpath(libdir, pkg_out)
        for ts, future in eps.items():
            link([future.result()], pkg_out / f"{pkg}_s__{ts}{ext}",
                 [*own("rosidl_generator_py", ts, "rosidl_typesupport_c", "rosidl_generator_c"),
                  "-lrosidl_typesupport_c", "-lrosidl_runtime_c"], rel)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ros-python", default=sys.executable,
                    help="Python of the ros-jazzy-* venv (runs the rosidl generators)")
    ap.add_argument("--out", required=True, type=Path,
                    help="folder to put the Python package in (goes on PYTHONPATH)")
    ap.add_argument("--libdir", type=Path, help="folder for the shared libraries "
                    "(goes on LD_LIBRARY_PATH); default OUT/lib")
    ap.add_argument("--src", type=Path, default=SRC, help="the package's definitions folder")
    ap.add_argument("--build", type=Path, help="keep the generated sources here "
                    "(default: a temporary folder)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    a = ap.parse_args()
    a.out, a.src = a.out.resolve(), a.src.resolve()
    a.libdir = (a.libdir or a.out / "lib").resolve()
    ros_prefix = Path(a.ros_python).parents[1].resolve()
    if Path(sys.prefix).resolve() != ros_prefix:  # re-run under the ROS venv's Python
        argv = [a.ros_python, __file__, "--out", str(a.out), "--libdir", str(a.libdir),
                "--src", str(a.src), "--jobs", str(a.jobs)]
        argv += ["--build", str(a.build.resolve())] if a.build else []
        raise SystemExit(subprocess.run(argv).returncode)
    pkg = a.src.name
    files = interface_files(a.src)
    deps = dependencies(a.src, files, pkg)
    with contextlib.ExitStack() as stack:
        gen = a.build.resolve() if a.build else Path(stack.enter_context(
            tempfile.TemporaryDirectory(prefix="rosidl_")))
        gen.mkdir(parents=True, exist_ok=True)
        supports = run_generators(pkg, a.src, files, deps, ros_prefix, gen)
        compile_all(pkg, deps, ros_prefix, gen, a.out, a.libdir, supports, a.jobs)
    print(f"built {pkg} ({len(files)} interfaces; deps {', '.join(deps)}; type supports "
          f"{', '.join(supports)}): PYTHONPATH={a.out} LD_LIBRARY_PATH={a.libdir}")


if __name__ == "__main__":
    main()

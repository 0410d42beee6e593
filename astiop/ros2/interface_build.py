"""Build the robot's interface packages into a ROS 2 prefix with plain cmake.

`astiop_msgs` is astiop's own ament package (`packages/astiop_msgs`). The standard packages the
catalog names that have no PyPI wheel (nav2_msgs' NavigateToPose, tf2_msgs' TFMessage) are
built as subsets from astiop's definitions only where they are not importable: on a robot the
real ones are installed. The field text is upstream's, so the type hashes match and a real client
of those types interoperates. The same sources build with `colcon build` on a robot
(`export_packages`).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from astiop.ros2.definitions import ASTIOP_MSGS, definitions

# The subsets built where upstream's package is absent: package -> (its types, dependencies)
SUBSETS = {
    "nav2_msgs": (
        ("nav2_msgs/action/NavigateToPose",),
        ("builtin_interfaces", "geometry_msgs", "std_msgs"),  # Humble's result is std_msgs/Empty
    ),
    "tf2_msgs": (("tf2_msgs/msg/TFMessage",), ("geometry_msgs",)),
}
ASTIOP_DEPENDENCIES = ("std_msgs", "geometry_msgs")
STAMP = "astiop-build.stamp"  # in share/<package>/: the hash of what was built
# The msg wheels' exported CMake files name the Python of the machine that built the wheels
# (ycheng517/ros-python-wheels, manylinux): its headers and numpy's. A package that depends on
# them must find this machine's instead, or rosidl's Python extension does not compile.
WHEEL_PYTHON = "/opt/python/cp311-cp311/"


class BuildError(Exception):
    """A tool is missing or cmake failed: one line that says what to do."""


@dataclass
class BuildReport:
    built: list[str] = field(default_factory=list)
    up_to_date: list[str] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)  # package -> why it was not built
    repaired: list[Path] = field(default_factory=list)
    seconds: float = 0.0


def ros_distro(prefix: Path) -> str:
    """The distro of the ROS 2 in `prefix` (wheels) or of the sourced install."""
    for distro in ("kilted", "jazzy", "humble"):
        if (prefix / "share" / "ament_index").is_dir() and _has_wheel(f"ros-{distro}-rclpy"):
            return distro
    return os.environ.get("ROS_DISTRO", "jazzy")


def _has_wheel(name: str) -> bool:
    from importlib import metadata

    try:
        metadata.version(name)
    except metadata.PackageNotFoundError:
        return False
    return True


def importable(package: str) -> bool:
    try:
        return importlib.util.find_spec(f"{package}.msg") is not None or bool(
            importlib.util.find_spec(f"{package}.action")
        )
    except (ImportError, ValueError):
        return False


def package_sources(package: str, distro: str) -> dict[str, str]:
    """Relative path -> text of the package's sources (package.xml, CMakeLists.txt, types)."""
    if package == "astiop_msgs":
        return {
            str(f.relative_to(ASTIOP_MSGS)): f.read_text(encoding="utf-8")
            for f in sorted(ASTIOP_MSGS.rglob("*"))
            if f.is_file()
        }
    types, deps = SUBSETS[package]
    defs = definitions(distro)
    files = {}
    for name in types:
        _, kind, leaf = name.split("/")
        files[f"{kind}/{leaf}.{kind}"] = defs[name]
    return {
        "package.xml": _package_xml(package, deps),
        "CMakeLists.txt": _cmakelists(package, sorted(files), deps),
        **files,
    }


def _package_xml(package: str, deps: tuple[str, ...]) -> str:
    depends = "".join(f"  <depend>{d}</depend>\n" for d in deps)
    return f"""<?xml version="1.0"?>
<package format="3">
  <name>{package}</name>
  <version>0.0.0</version>
  <description>A subset of {package} (built by astiop where {package} is not installed)</description>
  <maintainer email="astiop@example.org">astiop</maintainer>
  <license>Apache-2.0</license>
  <buildtool_depend>ament_cmake</buildtool_depend>
  <buildtool_depend>rosidl_default_generators</buildtool_depend>
{depends}  <exec_depend>rosidl_default_runtime</exec_depend>
  <member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def _cmakelists(package: str, files: list[str], deps: tuple[str, ...]) -> str:
    finds = "".join(f"find_package({d} REQUIRED)\n" for d in deps)
    listed = "".join(f'  "{f}"\n' for f in files)
    return f"""cmake_minimum_required(VERSION 3.8)
project({package})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{finds}rosidl_generate_interfaces(${{PROJECT_NAME}}
{listed}  DEPENDENCIES {" ".join(deps)}
)
ament_export_dependencies(rosidl_default_runtime)
ament_package()
"""


def export_packages(folder: Path, distro: str, packages: tuple[str, ...] = ()) -> list[Path]:
    """Write the packages' sources under `folder` (a colcon workspace's src/, say)."""
    return [
        _write_sources(folder / package, package_sources(package, distro))
        for package in packages or ("astiop_msgs", *SUBSETS)
    ]


def _write_sources(root: Path, sources: dict[str, str]) -> Path:
    for rel, text in sources.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text, encoding="utf-8")
    return root


def _source_hash(sources: dict[str, str], distro: str) -> str:
    h = hashlib.sha256(f"{distro} {sys.version_info[:2]}".encode())
    for rel in sorted(sources):
        h.update(rel.encode() + b"\0" + sources[rel].encode() + b"\0")
    return h.hexdigest()


def check_tools(prefix: Path) -> None:
    if shutil.which("cmake") is None:
        raise BuildError(
            "cmake is not on PATH: install it (apt install cmake, or pip install cmake)"
        )
    if not any(shutil.which(cc) for cc in ("cc", "gcc", "clang")):
        raise BuildError("no C compiler on PATH: install one (apt install build-essential)")
    if not _ament_prefixes(prefix) or not any(
        (p / "share" / "rosidl_default_generators").is_dir() for p in _ament_prefixes(prefix)
    ):
        raise BuildError(
            'the ROS 2 interface generators are not installed: pip install "astiop[ros]" '
            "(or source your ROS 2 setup.bash)"
        )


def _ament_prefixes(prefix: Path) -> list[Path]:
    found = [prefix] + [Path(p) for p in os.environ.get("AMENT_PREFIX_PATH", "").split(":") if p]
    return [p for p in dict.fromkeys(found) if (p / "share").is_dir()]


def repair_wheel_cmake(prefix: Path) -> list[Path]:
    """Point the wheels' exported CMake files at this machine's Python and numpy headers."""
    cmake_dirs = (prefix / "share").glob("*/cmake")
    include = sysconfig.get_paths()["include"]
    try:
        import numpy

        np_include = numpy.get_include()
    except ImportError:
        np_include = ""
    repaired = []
    for folder in cmake_dirs:
        for f in folder.glob("*.cmake"):
            text = f.read_text(encoding="utf-8", errors="replace")
            if WHEEL_PYTHON not in text:
                continue
            text = text.replace(f"{WHEEL_PYTHON}include/python3.11", include)
            if np_include:
                text = text.replace(
                    f"{WHEEL_PYTHON}lib/python3.11/site-packages/numpy/_core/include", np_include
                )
            f.write_text(text, encoding="utf-8")
            repaired.append(f)
    return repaired


def build(
    prefix: Path,
    *,
    say: Callable[[str], None] = print,
    packages: tuple[str, ...] = (),
    jobs: int = 2,
) -> BuildReport:
    """Build what is missing or out of date into `prefix`; a second run is a no-op."""
    t0 = time.monotonic()
    report = BuildReport()
    distro = ros_distro(prefix)
    wanted = packages or ("astiop_msgs", *SUBSETS)
    todo: list[tuple[str, dict[str, str], str]] = []
    for package in wanted:
        sources = package_sources(package, distro)
        digest = _source_hash(sources, distro)
        stamp = prefix / "share" / package / STAMP
        ours = stamp.is_file()
        if ours and stamp.read_text().strip() == digest and importable(package):
            report.up_to_date.append(package)
        elif package in SUBSETS and not ours and importable(package):
            report.skipped[package] = "installed already (the real package)"
        else:
            todo.append((package, sources, digest))
    if not todo:
        report.seconds = time.monotonic() - t0
        return report
    check_tools(prefix)
    report.repaired = repair_wheel_cmake(prefix)
    if report.repaired:
        say(
            f"repaired {len(report.repaired)} CMake files of the ROS wheels that name the wheels' "
            f"build machine's Python ({WHEEL_PYTHON}): they now name this one's headers"
        )
    work = prefix / "share" / "astiop" / "interface-build"
    env = _build_env(prefix)
    for package, sources, digest in todo:  # none of them needs another's build
        say(f"building {package} ({distro}) into {prefix} …")
        shutil.rmtree(work / "src" / package, ignore_errors=True)  # no file of an older build
        src = _write_sources(work / "src" / package, sources)
        _cmake(src, work / "build" / package, prefix, env, jobs)
        (prefix / "share" / package / STAMP).write_text(digest + "\n", encoding="utf-8")
        report.built.append(package)
    importlib.invalidate_caches()
    report.seconds = time.monotonic() - t0
    return report


def _build_env(prefix: Path) -> dict[str, str]:
    env = dict(os.environ)
    prefixes = ":".join(str(p) for p in _ament_prefixes(prefix))
    env["AMENT_PREFIX_PATH"] = prefixes
    env["CMAKE_PREFIX_PATH"] = ":".join(filter(None, [prefixes, env.get("CMAKE_PREFIX_PATH")]))
    env["PATH"] = f"{Path(sys.executable).parent}:{env.get('PATH', '')}"
    return env


def _cmake(src: Path, build_dir: Path, prefix: Path, env: dict[str, str], jobs: int) -> None:
    steps = [
        [
            "cmake", "-S", str(src), "-B", str(build_dir), f"-DCMAKE_INSTALL_PREFIX={prefix}",
            f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF",
        ],
        ["cmake", "--build", str(build_dir), "-j", str(jobs)],
        ["cmake", "--install", str(build_dir)],
    ]  # fmt: skip
    for argv in steps:
        out = subprocess.run(argv, env=env, capture_output=True, text=True)
        if out.returncode != 0:
            log = build_dir / "astiop-build.log"
            log.parent.mkdir(parents=True, exist_ok=True)
            log.write_text(out.stdout + out.stderr, encoding="utf-8")
            raise BuildError(
                f"{src.name}: `{' '.join(argv[:2])}` failed: {_first_error(out)} (log: {log})"
            )


def _first_error(out: subprocess.CompletedProcess) -> str:
    for line in (out.stderr + out.stdout).splitlines():
        if "error" in line.lower():
            return line.strip()[:200]
    return f"exit {out.returncode}"

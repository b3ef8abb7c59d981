"""Builds the extension delta._delta with CMake, for pyproject.toml's setuptools backend.

The version is the CMake project's. CMake configures a build with only the library and the
module (no tests, benchmarks, command-line tool or MPI), for the interpreter running this
script, in setuptools' build_temp folder; the module links the static library, so the wheel
needs only the system's shared libraries the library itself needs (assimp, qhull, OpenMP's
runtime: Debian's libassimp5, libqhull-r8.0, libgomp1). Environment: CMAKE_ARGS (extra options,
split on spaces), CMAKE_BUILD_PARALLEL_LEVEL (jobs), CMAKE_CXX_COMPILER_LAUNCHER (e.g. ccache).
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(delta\s+VERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError("setup.py: no `project(delta VERSION ...)` in CMakeLists.txt")
    return match.group(1)


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        build = Path(self.build_temp).resolve() / "cmake"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build),
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",
            "-DBUILD_SHARED_LIBS=OFF",
            "-DDELTA_BUILD_PYTHON=ON",
            "-DDELTA_BUILD_TESTS=OFF",
            "-DDELTA_BUILD_BENCH=OFF",
            "-DDELTA_BUILD_APPS=OFF",
            "-DDELTA_WITH_MPI=OFF",
        ]
        if shutil.which("ninja"):
            configure += ["-G", "Ninja"]
        configure += [arg for arg in os.environ.get("CMAKE_ARGS", "").split() if arg]
        subprocess.run(configure, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build), "--target", "delta_python",
                        "--parallel", jobs], check=True)
        built = sorted((build / "python" / "delta").glob("_delta*.so"))
        if len(built) != 1:
            raise RuntimeError(f"setup.py: expected one extension in {build}/python/delta, found {built}")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


# setuptools' folders go to build-python/, beside CMake's build folders (its default, build/, is
# the folder scripts/setup.sh configures).
BUILD_BASE = "build-python"
(ROOT / BUILD_BASE).mkdir(exist_ok=True)

setup(
    version=project_version(),
    options={"build": {"build_base": BUILD_BASE}, "egg_info": {"egg_base": BUILD_BASE}},
    ext_modules=[CMakeExtension("delta._delta")],
    cmdclass={"build_ext": CMakeBuild},
)

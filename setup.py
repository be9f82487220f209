"""pip install . : the Python module msii, built by CMake (pyproject.toml has the metadata).

CMake builds only the module (MSII_PYTHON_WHEEL), with the engine linked into it statically,
so the wheel holds one file and needs no libmsii beside it. The CMake build folder stays in
.pip-build/ of the source tree, so a second `pip install .` rebuilds only what changed.
Environment: CMAKE_BUILD_PARALLEL_LEVEL (default: the number of cores), MSII_CMAKE_ARGS
(further -D options, space-separated).
"""
import os
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = Path(__file__).resolve().parent


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name)).resolve()
        build = SOURCE / ".pip-build" / f"cmake-py{sys.version_info.major}.{sys.version_info.minor}"
        configure = [
            "cmake", "-S", str(SOURCE), "-B", str(build),
            "-DCMAKE_BUILD_TYPE=Release",
            "-DMSII_PYTHON_WHEEL=ON",
            # The interpreter pip runs (a virtual environment's), for the module's suffix.
            f"-DPython_EXECUTABLE={sys.executable}",
        ] + shlex.split(os.environ.get("MSII_CMAKE_ARGS", ""))
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "msii_python", "-j", jobs], check=True)
        built = sorted((build / "python").glob("msii.*.so"))
        if len(built) != 1:
            sys.exit(f"msii: expected one built module in {build / 'python'}, found {built}")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


setup(
    ext_modules=[CMakeExtension("msii")],
    cmdclass={"build_ext": CMakeBuild},
    packages=[],
    py_modules=[],
    # setuptools' own build folders beside CMake's, not in build/ (tools/setup.sh's CMake build).
    options={"build": {"build_base": str(SOURCE / ".pip-build" / "setuptools")}},
)

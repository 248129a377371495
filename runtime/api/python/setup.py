"""pip install runtime/api/python: configures PointRT with CMake (the checkout two folders up, no
tests), builds the target prt_python and installs the module it makes. Needs CMake, a C++20
compiler and Debian's build dependencies (scripts/install-deps.sh, pybind11-dev among them);
CUDA is built where nvcc exists. Environment: PRT_CMAKE_ARGS adds configure options, PRT_JOBS
sets the parallel jobs (default 2)."""
import glob
import os
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        if not os.path.exists(os.path.join(ROOT, "runtime", "api", "python", "pointrt_module.cpp")):
            sys.exit("pointrt: build from the PointRT checkout (pip install runtime/api/python, in-tree)")
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        cfg = ["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DPRT_BUILD_TESTS=OFF",
               "-DPRT_WITH_PYTHON=ON", "-DPython_EXECUTABLE=" + sys.executable]
        if shutil.which("ccache"):
            cfg.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
        cfg += shlex.split(os.environ.get("PRT_CMAKE_ARGS", ""))
        subprocess.check_call(cfg)
        subprocess.check_call(["cmake", "--build", build, "--target", "prt_python", "-j", os.environ.get("PRT_JOBS", "2")])
        built = glob.glob(os.path.join(build, "python", "pointrt*.so"))
        if not built:
            sys.exit("pointrt: the build made no module in " + os.path.join(build, "python"))
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)


setup(ext_modules=[Extension("pointrt", sources=[])], cmdclass={"build_ext": CMakeBuild})

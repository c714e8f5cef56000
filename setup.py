"""pip install . : the compiled module mbsflow._core built by the project's CMake, with the
mbsflow libraries static inside it (the package needs no libmbsflow_*.so beside it), and
the package's Python files from python/mbsflow. Configuration: pyproject.toml."""
import glob
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        generator = ["-G", "Ninja"] if shutil.which("ninja") else []
        subprocess.check_call(["cmake", "-S", HERE, "-B", build, *generator, "-DCMAKE_BUILD_TYPE=Release",
                               "-DMBSFLOW_SHARED=OFF", "-DCMAKE_POSITION_INDEPENDENT_CODE=ON",
                               "-DMBSFLOW_BUILD_TESTS=OFF", f"-DMBSFLOW_PYTHON={sys.executable}"])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        subprocess.check_call(["cmake", "--build", build, "--target", "mbsflow_python", "-j", jobs])
        built = glob.glob(os.path.join(build, "python", "mbsflow", "_core*.so"))
        if not built:
            raise RuntimeError("the CMake build made no mbsflow/_core module")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(built[0], target)


setup(packages=["mbsflow"], package_dir={"": "python"},
      ext_modules=[Extension("mbsflow._core", sources=[])], cmdclass={"build_ext": CMakeBuild})

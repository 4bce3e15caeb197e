"""Builds ur10core's optional compiled kernel; everything else is in pyproject.toml.

Without a C compiler the build of ``ur10core._kernels`` fails quietly (``optional=True``)
and ur10core runs on numpy (``ur10core.BACKEND == "numpy"``).
"""

import numpy
from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

# no fast-math anywhere: NaN marks invalid slots and must survive
FLAGS = {"msvc": ["/O2"], "unix": ["-O3", "-std=c99", "-fno-math-errno"]}


class BuildExt(build_ext):
    def build_extensions(self):
        for extension in self.extensions:
            extension.extra_compile_args = FLAGS.get(self.compiler.compiler_type, [])
        super().build_extensions()


setup(
    ext_modules=[
        Extension("ur10core._kernels", ["ur10core/_kernels.c"], include_dirs=[numpy.get_include()], optional=True)
    ],
    cmdclass={"build_ext": BuildExt},
)

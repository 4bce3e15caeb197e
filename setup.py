"""Builds ur10core's compiled IK kernel; everything else is in pyproject.toml."""

import numpy
from setuptools import Extension, setup

setup(
    ext_modules=[
        Extension(
            "ur10core._kernels",
            ["ur10core/_kernels.c"],
            include_dirs=[numpy.get_include()],
            # no -ffast-math: NaN marks invalid slots and must survive
            extra_compile_args=["-O3", "-std=c99", "-fno-math-errno"],
        )
    ]
)

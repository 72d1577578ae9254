"""The simulator's C loops (sim/native.c), a plain C library that sim/native.py loads with
ctypes; everything else about the package is in pyproject.toml. Built to give Python's
float arithmetic bit for bit: no a*b+c contracted into one rounding, and sin and cos
called as written (not merged into one sincos call)."""

from setuptools import Extension, setup

setup(ext_modules=[Extension(
    "gliderplan.sim._native", ["sim/native.c"], libraries=["m"],
    extra_compile_args=["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-ffp-contract=off",
                        "-fno-builtin-sin", "-fno-builtin-cos"])])

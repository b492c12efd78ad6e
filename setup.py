"""Builds the compiled parts: the private ODE binding against the system libode
(engine/physics/ode3d/_ode.pyx, which includes the .pxi files beside it, one per concept,
cimports their libode.pxd declarations and includes stepper.h, the step policy it shares
with app/bench/bench_ode.c, and through it engine/physics/sleep.h), the sleep rule's per-body
pass (engine/physics/_sleep.pyx, over sleep.h), the passes that read chipmunk (through
pymunk's cffi library) into engine rows (engine/physics/pymunk2d/_rows.pyx), the scene scanner
(engine/scene/_scan.pyx) and the network pose codec's per-frame passes
(services/net/_codec.pyx: built without fused multiply-add, so every machine's arithmetic
is the same to the bit, as a server's copy of the poses and its nodes' must be), and the
skeletons' hierarchy and palettes (engine/animation/_compose.pyx), and the fingered hands'
per-frame arithmetic (systems/_fingers.pyx)."""

import shlex
import subprocess
from pathlib import Path

import numpy
from setuptools import Extension, setup


def pkg_config(flag: str) -> list[str]:
    try:
        out = subprocess.run(["pkg-config", flag, "ode"], check=True, capture_output=True,
                             text=True)
    except (OSError, subprocess.CalledProcessError) as exc:
        raise SystemExit(
            "colosseum: cannot find libode with pkg-config; install it with "
            "`sudo apt-get install libode-dev pkg-config` (or run tools/dev setup)"
        ) from exc
    return shlex.split(out.stdout)


def extensions() -> list[Extension]:
    source = Path("engine/physics/ode3d/_ode.pyx")
    if not source.exists():
        return []
    from Cython.Build import cythonize

    cflags = pkg_config("--cflags")
    ext = Extension(
        "engine.physics.ode3d._ode",
        [str(source)],
        include_dirs=[numpy.get_include(), "engine/physics"],  # sleep.h (csleep.pxd)
        extra_compile_args=[*cflags, "-O3", "-DdDOUBLE"],
        libraries=["ode"],
        library_dirs=[a[2:] for a in pkg_config("--libs") if a.startswith("-L")],
        define_macros=[("NPY_NO_DEPRECATED_API", "NPY_1_7_API_VERSION")],
        depends=["engine/physics/ode3d/stepper.h", "engine/physics/sleep.h",
                 "engine/physics/policy.h"],
    )
    sleep = Extension("engine.physics._sleep", ["engine/physics/_sleep.pyx"],
                      extra_compile_args=["-O3"], depends=["engine/physics/sleep.h"])
    scan = Extension("engine.scene._scan", ["engine/scene/_scan.pyx"],
                     extra_compile_args=["-O3"])
    rows = Extension("engine.physics.pymunk2d._rows", ["engine/physics/pymunk2d/_rows.pyx"],
                     include_dirs=[numpy.get_include(), "engine/physics"],  # policy.h
                     depends=["engine/physics/policy.h"],
                     extra_compile_args=["-O3", "-ffp-contract=off"],  # no fused a*b+c
                     define_macros=[("NPY_NO_DEPRECATED_API", "NPY_1_7_API_VERSION"),
                                    ("_GNU_SOURCE", None)])  # sincos
    codec = Extension("services.net._codec", ["services/net/_codec.pyx"],
                      extra_compile_args=["-O3", "-ffp-contract=off"])
    compose = Extension("engine.animation._compose", ["engine/animation/_compose.pyx"],
                        extra_compile_args=["-O3"])
    fingers = Extension("systems._fingers", ["systems/_fingers.pyx"],
                        include_dirs=[numpy.get_include()], extra_compile_args=["-O3"],
                        define_macros=[("NPY_NO_DEPRECATED_API", "NPY_1_7_API_VERSION")])
    return cythonize([ext, sleep, rows, scan, codec, compose, fingers], language_level=3,
                     compiler_directives={"boundscheck": False, "wraparound": False})


setup(ext_modules=extensions())

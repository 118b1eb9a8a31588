"""
Sizes of every study of the error report
========================================

:data:`QUICK` (``--quick``: a smoke run of every section in well under a minute on
2 cores) and :data:`FULL` (the committed ``docs/report``). Angles in radians,
turbidity dimensionless; counts are counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Plan:
    """Sizes of every study (the section that uses a field is its prefix or its comment)."""

    name: str
    s1_points: tuple[tuple[float, float], ...]  # (sun zenith, turbidity) of section 1
    s1_samples: tuple[int, ...]  # directions of the random projection methods
    s1_seeds: int
    s1_nodes: tuple[int, ...]  # Gauss nodes per panel of the quadratures
    truth_nodes: int  # nodes per panel of section 1's truth
    test_grid: tuple[int, int]  # held-out uniform grid of sections 2, 3, 8, 9
    grid_nodes: int | None  # Gauss nodes per panel of the truth at grid points (None: sky_sh's default)
    fit_grid: tuple[int, int]  # Chebyshev fitting grid of sections 3, 8
    degrees_theta: tuple[int, ...]  # degrees swept in section 3
    degrees_tau: tuple[int, ...]
    timing: tuple[int, int]  # (rounds, calls per round) of the runtime timings
    gibbs_suns: tuple[tuple[float, float], ...]  # section 4
    dering_grid: tuple[int, int]  # section 5
    dering_seven: int  # 7-band skies of section 5
    random_functions: int  # random 3-band functions of the bound study (section 5)
    table3_points: int  # section 6
    bits: tuple[int, ...]
    hazel_points: int  # section 7
    hazel_zeniths: tuple[float, ...]
    stability_degrees: tuple[tuple[int, int], ...]  # section 8
    extrapolation: tuple[int, tuple[float, ...]]  # (turbidities, sun zeniths)
    mc_counts: tuple[int, ...]
    mc_seeds: int
    mc_points: tuple[tuple[float, float], ...]
    fuzz_inputs: int
    scene_points: int  # section 9
    picture_suns: tuple[tuple[float, float, float], ...]  # section 10: (zenith, azimuth, turbidity)
    picture_width: int


_D = math.radians

QUICK = Plan(
    name="quick",
    s1_points=((_D(40.0), 3.5), (_D(85.0), 5.0)),
    s1_samples=(64, 256, 1024, 4096),
    s1_seeds=2,
    s1_nodes=(8, 16, 32),
    truth_nodes=96,
    test_grid=(8, 5),
    grid_nodes=32,
    fit_grid=(16, 8),
    degrees_theta=(3, 7, 13),
    degrees_tau=(1, 3, 7),
    timing=(3, 30),
    gibbs_suns=((_D(30.0), 3.0), (_D(80.0), 2.5)),
    dering_grid=(7, 4),
    dering_seven=4,
    random_functions=1000,
    table3_points=32,
    bits=(4, 8, 12),
    hazel_points=2,
    hazel_zeniths=(_D(10.0), _D(88.0)),
    stability_degrees=((5, 3), (13, 7)),
    extrapolation=(6, (_D(30.0), _D(80.0))),
    mc_counts=(4, 16, 64, 256),
    mc_seeds=10,
    mc_points=((_D(70.0), 3.0),),
    fuzz_inputs=300,
    scene_points=2,
    picture_suns=((_D(25.0), _D(30.0), 2.5), (_D(85.0), _D(-60.0), 4.0)),
    picture_width=128,
)
"""Small sizes: every section in well under a minute (the test suite's smoke run)."""

FULL = Plan(
    name="full",
    s1_points=((_D(10.0), 2.5), (_D(45.0), 3.5), (_D(75.0), 5.0), (_D(89.0), 6.0)),
    s1_samples=(64, 256, 1024, 4096, 16384, 65536),
    s1_seeds=8,
    s1_nodes=(8, 11, 16, 23, 32, 45, 64, 90),
    truth_nodes=160,
    test_grid=(46, 22),
    grid_nodes=None,
    fit_grid=(48, 24),
    degrees_theta=(3, 5, 7, 9, 11, 13, 15, 17),
    degrees_tau=(1, 2, 3, 5, 7, 9),
    timing=(5, 200),
    gibbs_suns=((_D(10.0), 2.5), (_D(45.0), 3.5), (_D(75.0), 3.0), (_D(89.0), 2.5)),
    dering_grid=(19, 8),
    dering_seven=24,
    random_functions=20000,
    table3_points=1024,
    bits=(4, 5, 6, 8, 10, 12, 16),
    hazel_points=64,
    hazel_zeniths=tuple(_D(z) for z in (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0, 85.0, 88.0, 90.0)),
    stability_degrees=((3, 1), (5, 3), (7, 3), (9, 5), (11, 5), (13, 7), (15, 7), (17, 9)),
    extrapolation=(25, (_D(30.0), _D(60.0), _D(85.0))),
    mc_counts=(4, 8, 16, 32, 64, 128, 256, 1024, 4096),
    mc_seeds=200,
    mc_points=((_D(30.0), 3.0), (_D(70.0), 3.0), (_D(88.0), 2.5)),
    fuzz_inputs=5000,
    scene_points=16,
    picture_suns=((_D(25.0), _D(30.0), 2.5), (_D(65.0), _D(120.0), 4.0), (_D(88.0), _D(-60.0), 6.0)),
    picture_width=256,
)
"""The committed report's sizes: the shipped fitting grid, a dense held-out grid, many seeds."""

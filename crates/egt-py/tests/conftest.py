"""Shared fixtures: the paper's trains written inline (so the tests do not
depend on the bundled examples' numbers), and the path to the examples."""

from __future__ import annotations

import pathlib

import pytest

import egt

ROOT = pathlib.Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"

# Fig. 3 / example 6.1: frame 1, input carrier 2, compound planet 3 (three
# copies), output 4. tau_1 = -20/30, tau_2 = -32/18.
FIG3 = """
name = "Fig. 3"
frame = "1"

[[links]]
name = "2"
inertia = 2.0e-3
mass = 1.5

[[links]]
name = "3"
inertia = 4.0e-5
mass = 0.12
copies = 3

[[links]]
name = "4"
inertia = 1.2e-3

[[revolutes]]
links = ["1", "2"]
level = "a"

[[revolutes]]
links = ["2", "3"]
level = "b"

[[revolutes]]
links = ["1", "4"]
level = "a"

[[gears]]
name = "G1"
links = ["1", "3"]
teeth = [30, 20]
mesh = "external"
module = 2.0e-3
efficiency = 0.98

[[gears]]
name = "G2"
links = ["3", "4"]
teeth = [18, 32]
mesh = "external"
module = 2.0e-3
efficiency = 0.98

[analysis]
speeds = { "2" = 100 }
torques = { "4" = -50.0 }
accelerations = { "4" = 10.0 }
driving = ["2"]
reduce_to = "2"
"""

# Fig. 5 / example 6.2 (Table 2 with 6 at level b, see docs/errata.md): two
# motors on 2 and 4, output ring 6.
FIG5 = """
name = "Fig. 5"
frame = "1"

[[links]]
name = "2"
inertia = 5.0e-4

[[links]]
name = "3"
inertia = 8.0e-3
mass = 2.0

[[links]]
name = "4"
inertia = 6.0e-4

[[links]]
name = "5"
inertia = 3.0e-5
mass = 0.1

[[links]]
name = "6"
inertia = 4.0e-3

[[revolutes]]
links = ["1", "2"]
level = "a"

[[revolutes]]
links = ["1", "3"]
level = "b"

[[revolutes]]
links = ["3", "5"]
level = "c"

[[revolutes]]
links = ["1", "4"]
level = "b"

[[revolutes]]
links = ["1", "6"]
level = "b"

[[gears]]
name = "G1"
links = ["2", "3"]
teeth = [20, 60]
mesh = "external"
module = 2.0e-3

[[gears]]
name = "G2"
links = ["5", "4"]
teeth = [20, 30]
mesh = "external"
module = 1.5e-3

[[gears]]
name = "G3"
links = ["5", "6"]
teeth = [20, 70]
mesh = "internal"
module = 1.5e-3

[analysis]
speeds = { "2" = 300, "4" = 100 }

[[analysis.curves]]
link = "2"
torque = 2.0
slope = -0.05
speed = 300.0

[[analysis.curves]]
link = "4"
torque = 3.0
slope = -0.08
speed = 100.0

[[analysis.curves]]
link = "6"
torque = -10.0
slope = -0.2
speed = -185.7
"""

# A simple planetary set with the ring fixed, written with the shorthand.
PLANETARY = """
frame = "housing"

[[planetary]]
name = "P"
sun = "sun"
ring = "housing"
carrier = "carrier"
teeth = { sun = 30, planet = 21, ring = 72 }
module = 1.5e-3
efficiency = 0.985

[[links]]
name = "sun"
inertia = 2.0e-4

[[links]]
name = "carrier"
inertia = 3.5e-3
mass = 1.8

[[links]]
name = "P.planet"
inertia = 1.5e-5
mass = 0.08
copies = 3
"""


@pytest.fixture
def fig3() -> egt.Train:
    return egt.loads(FIG3)


@pytest.fixture
def fig5() -> egt.Train:
    return egt.loads(FIG5)


@pytest.fixture
def planetary() -> egt.Train:
    return egt.loads(PLANETARY)

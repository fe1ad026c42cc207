"""rld: race-track lane detection from 2D cone maps.

The public contract (DESIGN.md): ``solve_lane``, ``LaneSolver``, ``LaneParams``, ``Lane``,
``LaneStatus`` and ``Pose``. Everything else is importable from its module.
"""

from rld.api import LaneSolver, solve_lane
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["solve_lane", "LaneSolver", "LaneParams", "Lane", "LaneStatus", "Pose"]
__version__ = "0.1.0"

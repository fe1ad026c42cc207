"""clc: the CLC path-pair enumeration of Ivanov & Markgraf (2024), built on ``rld``'s shared
geometry, constraints and costs. The search lands with issue 4."""

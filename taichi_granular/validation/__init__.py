"""The validation cases of ``taichi-granular validate``: :data:`CASES` is the one registry (the
command's choices and help come from it). A case names its scene files (the coarse CPU
variants; ``--resolution paper`` swaps in the paper's) and the module of this package whose
``check(case, runs, base, args) -> bool`` measures each run against its reference, prints the
errors, writes its files and applies the acceptance rule (its thresholds live there too); a
module may offer ``prepare(args)``, a function that sets the initial state before a run.
"""
import importlib
from dataclasses import dataclass
from typing import Tuple


@dataclass(frozen=True)
class ValidationCase:
    name: str  # the command's choice
    summary: str  # one line for --help
    module_name: str  # the module of this package that checks it
    folder: str = ""  # its scenes: configs/<folder>/<patterns>
    patterns: Tuple[str, ...] = ()  # none: the case runs no scene file (element tests)

    def module(self):
        return importlib.import_module(f"{__name__}.{self.module_name}")


CASES = {case.name: case for case in (
    ValidationCase("inclined-plane", "steady flow down a slope: mu(I) against [M56], hypoplastic against its "
                   "bounding slopes", "inclined_plane", "mu_i", ("inclined_plane.yaml",)),
    ValidationCase("column-collapse", "2D mu(I) column collapses of [M] Table 3 against Lube et al. (2004)",
                   "column_collapse", "mu_i", ("collapse_a*.yaml",)),
    ValidationCase("column-collapse-3d", "3D elastoplastic collapses of [A] against Lube et al. (2004)",
                   "column_collapse", "elastoplastic", ("collapse3d_a*_coarse.yaml",)),
    ValidationCase("pile-collapse", "2D hypoplastic collapse (set 2 of [P]) against Lube et al. (2004)",
                   "column_collapse", "hypoplastic", ("collapse_a*.yaml",)),
    ValidationCase("stake-rows", "stake rows of [A]: efficiency factors against Yellin et al. (2013)",
                   "obstacles", "elastoplastic", ("stake_rows_case*_coarse.yaml",)),
    ValidationCase("obstacle-flow", "cylinder and wedge of [A]: bow shock, wake, protected zone",
                   "obstacle_flow", "elastoplastic", ("cylinder_coarse.yaml", "wedge_coarse.yaml")),
    ValidationCase("element-tests", "hypoplastic element tests and the annular shear cell of [P]", "element_tests"),
    ValidationCase("drum", "rotating drum of [P] at omega = 0.5, 1, 2 rad/s", "drum", "hypoplastic",
                   ("drum_omega*_coarse.yaml",)),
)}

#!/usr/bin/env python3
"""Writes the ladder of `benches/common/chains.rs` (`ladder_program`: N parallelograms between a
beam swinging from the ground and a rail of N segments, the loops sharing their rungs, mobility
2) to a file, to time the commands on it:

    python3 bench/ladder_program.py 1000 /tmp/ladder1000.lsd
    /usr/bin/time -f "%U %S %M" target/release/lsdc check /tmp/ladder1000.lsd

The text is the same as the Rust generator's, number for number (`{:.17}` formats as `%.17f`).
"""

import math
import sys

PREAMBLE = (
    "import joints ;\nimport gravity ;\nlet z = [0, 0, 1] ;\n"
    "let down = [0, -9.81, 0] ;\n"
    "let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, "
    "inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n"
)


def ladder_program(n):
    parts = [PREAMBLE]
    parts.append(f"let beam = bar({n}.0) ;\njoin earth and beam with revolute(z) as swing ;\n")
    parts.append("apply weight_in(beam, down) on beam.iframe ;\n")
    rung = -math.pi / 2 + 0.3
    initial = ["swing.q = 0 fixed"]
    for i in range(n + 1):
        parts.append(f"let rung{i} = bar(0.5) ;\n")
        parts.append(f"join [{i}.0, 0, 0] ++ 1 @ beam and rung{i} with revolute(z) as r{i} ;\n")
        parts.append(f"apply weight_in(rung{i}, down) on rung{i}.iframe ;\n")
        initial.append(f"r0.q = {rung:.17f} fixed" if i == 0 else f"r{i}.q = {rung:.17f}")
    for i in range(1, n + 1):
        parts.append(f"let rail{i} = bar(1.0) ;\n")
        parts.append(
            f"join [0.5, 0, 0] ++ 1 @ rung{i - 1} and rail{i} with revolute(z) as s{i} ;\n"
        )
        parts.append(f"apply weight_in(rail{i}, down) on rail{i}.iframe ;\n")
        parts.append(
            f"join [1.0, 0, 0] ++ 1 @ rail{i} and [0.5, 0, 0] ++ 1 @ rung{i} "
            f"with revolute(z) as e{i} ;\n"
        )
        initial.append(f"s{i}.q = {-rung:.17f}")
        initial.append(f"e{i}.q = {rung:.17f}")
    parts.append(f"initial {', '.join(initial)} ;\n")
    return "".join(parts)


if __name__ == "__main__":
    loops, path = int(sys.argv[1]), sys.argv[2]
    with open(path, "w") as out:
        out.write(ladder_program(loops))

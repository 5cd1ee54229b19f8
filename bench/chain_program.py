#!/usr/bin/env python3
"""Writes the generated chain of `benches/frontend.rs` (n bodies on revolute joints, a damper
torque and gravity on each) to a file, to measure `lsdc check` on it as a command:

    python3 bench/chain_program.py 100000 /tmp/chain100k.lsd
    /usr/bin/time -f "%U %S %M" target/release/lsdc check /tmp/chain100k.lsd
"""

import sys


def chain_program(n):
    parts = [
        "let g = 9.81;\n"
        "let hinge(axis) = link(q) dof = q || axis, torque = -0.1 * q' * axis end;\n"
    ]
    for i in range(1, n + 1):
        parts.append(
            f"let b{i} = body mass = 1.5, iframe = [0.25,0,0] ++ 1, "
            "inertia = [0.01,0.02,0.02] end;\n"
        )
        parent = "earth" if i == 1 else f"[0.5,0,0] ++ 1 @ b{i - 1}"
        parts.append(f"join {parent} and b{i} with hinge([0,0,1]);\n")
        parts.append(f"apply force value = [0,0,-g * b{i}.mass], body = earth end on b{i}.iframe;\n")
    return "".join(parts)


if __name__ == "__main__":
    bodies, path = int(sys.argv[1]), sys.argv[2]
    with open(path, "w") as out:
        out.write(chain_program(bodies))

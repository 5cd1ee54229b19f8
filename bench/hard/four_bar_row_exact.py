#!/usr/bin/env python3
"""The row of N parallelogram four-bars against its exact motion, to 30 digits.

The row has one degree of freedom: every crank turns by phi, the couplers translate, and
phi'' = -K cos(phi) / J (constants as in four_bar_row.py). phi(t) is integrated by mpmath's
Taylor method (mpmath.odefun) at 30 digits, and every number of an lsdc run's samples
(coordinates, rates, energies, momentum about the origin) is compared with its exact value by
the measure of tests/suite/native_loops.rs: max |x - exact| / (1 + |exact|).

Usage:
  bench/hard/four_bar_row_exact.py N RUN.json [RUN.json ...]
where RUN.json is `lsdc simulate examples/hard/four_bar_row_N.lsd --format json ...` output, or
  bench/hard/four_bar_row_exact.py N --fixture DURATION EVERY > FIXTURE.json
to write the exact samples at 0, EVERY, ..., DURATION in the shape of lsdc's JSON samples (each
number the double nearest its 30-digit value), with their provenance: the fixture the tests
compare runs with (tests/fixtures/hard/four_bar_row_2_exact.json).
"""

import json
import sys

import mpmath as mp

mp.mp.dps = 30
R, L, G = mp.mpf("0.5"), mp.mpf(1), mp.mpf("9.81")


def exact_samples(n, times):
    j = (n + 1) * R ** 3 / 3 + n * L * R ** 2
    k = G * R * ((n + 1) * R / 2 + n * L)
    phi_of = mp.odefun(lambda _, y: [y[1], -k * mp.cos(y[0]) / j], 0, [-mp.pi / 2, mp.mpf(12)])
    for t in times:
        phi, w = phi_of(mp.mpf(t))
        c, s = mp.cos(phi), mp.sin(phi)
        lz = px = py = mp.mpf(0)
        for i in range(n + 1):  # cranks: mass R, centre at (i L, 0) + R/2 (c, s), turning
            x, y, vx, vy = i * L + R / 2 * c, R / 2 * s, -R / 2 * w * s, R / 2 * w * c
            lz += R * (x * vy - y * vx) + R * R ** 2 / 12 * w
            px, py = px + R * vx, py + R * vy
        for i in range(1, n + 1):  # couplers: mass L, translating with the cranks' tips
            x, y, vx, vy = (i - 1) * L + L / 2 + R * c, R * s, -R * w * s, R * w * c
            lz += L * (x * vy - y * vx)
            px, py = px + L * vx, py + L * vy
        yield {
            "coordinates": [phi] * (n + 1) + [-phi] * n + [phi] * n,
            "rates": [w] * (n + 1) + [-w] * n + [w] * n,
            "kinetic_energy": j * w ** 2 / 2,
            "potential_energy": k * s,
            "momentum": [0, 0, lz, px, py, 0],
            "time": mp.mpf(t),
        }


def numbers(value):
    if isinstance(value, dict):
        return [x for key in sorted(value) if key != "work" for x in numbers(value[key])]
    if isinstance(value, list):
        return [x for item in value for x in numbers(item)]
    return [mp.mpf(value)]


def fixture(n, duration, every):
    count = round(mp.mpf(duration) / mp.mpf(every))
    times = [k * mp.mpf(every) for k in range(count + 1)]
    samples = [
        {key: [float(x) for x in value] if isinstance(value, list) else float(value)
         for key, value in sample.items()}
        for sample in exact_samples(n, times)
    ]
    provenance = (
        f"The row of {n} parallelogram four-bars (examples/hard/four_bar_row_{n}.lsd), its exact "
        "motion: phi'' = -K cos(phi) / J from phi = -pi/2, phi' = 12 rad/s, integrated by "
        f"mpmath {mp.__version__}'s Taylor method (mpmath.odefun) at {mp.mp.dps} digits; each "
        "number the double nearest its 30-digit value. Written by "
        f"`bench/hard/four_bar_row_exact.py {n} --fixture {duration} {every}`."
    )
    json.dump({"provenance": provenance, "samples": samples}, sys.stdout, indent=1)
    print()


def main():
    n = int(sys.argv[1])
    if sys.argv[2] == "--fixture":
        fixture(n, sys.argv[3], sys.argv[4])
        return
    runs = [json.load(open(path))["samples"] for path in sys.argv[2:]]
    exact = list(exact_samples(n, [s["time"] for s in runs[0]]))
    for path, samples in zip(sys.argv[2:], runs):
        apart = max(abs(x - e) / (1 + abs(e)) for x, e in zip(numbers(samples), numbers(exact)))
        print(f"{path}: {float(apart):.3e} from the exact motion")


if __name__ == "__main__":
    main()

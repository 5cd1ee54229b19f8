"""The Delta's positioning error under tolerances, from two sweeps of
examples/delta_tolerances.lsd read as Parquet by pandas (docs/commands.md, "sweep").

    lsdc sweep examples/delta_tolerances.lsd --design latin --sample 1000 --seed 1 \
        --vary "A1.q=uniform(0.7, 1.0)" ... (the arm angles and the tolerances) -o built.parquet
    python3 bench/delta_tolerances.py built.parquet

The nominal mechanism's nacelle at the same arm angles comes from a second sweep over the
angles alone (written by this script to nominal.csv, run with `lsdc sweep --values`, read back
as Parquet). The error is the distance between the two positions; the script prints its
percentiles, and its median over bands of the nominal nacelle's height (the workspace's depth).
"""
import subprocess
import sys

import pandas

ANGLES = ["A1.q", "A2.q", "A3.q"]
POSITION = ["end(nacelle.x)", "end(nacelle.y)", "end(nacelle.z)"]


def main(built_path, lsdc="lsdc"):
    built = pandas.read_parquet(built_path)
    built[ANGLES].to_csv("nominal.csv", index=False)
    subprocess.run(
        [lsdc, "sweep", "examples/delta_tolerances.lsd", "--values", "nominal.csv",
         "-o", "nominal.parquet"],
        check=True,
    )
    nominal = pandas.read_parquet("nominal.parquet")
    assert (built["run"].values == nominal["run"].values).all()
    ok = (built["status"] == "ok") & (nominal["status"] == "ok")
    difference = built.loc[ok, POSITION].values - nominal.loc[ok, POSITION].values
    error = pandas.Series((difference ** 2).sum(axis=1) ** 0.5, name="error")
    print(f"{ok.sum()} of {len(built)} runs assembled")
    print("error of the nacelle's position (micrometres):")
    print((1e6 * error.quantile([0.5, 0.9, 0.99, 1.0])).to_string())
    depth = pandas.cut(nominal.loc[ok, "end(nacelle.z)"].values, 4)
    by_depth = (1e6 * error).groupby(depth, observed=True).median()
    print("median error by the nominal nacelle's height z (m):")
    print(by_depth.to_string())


if __name__ == "__main__":
    main(*sys.argv[1:])

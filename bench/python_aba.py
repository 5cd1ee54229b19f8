"""ABA on a batch of 10,000 states from Python (`Prepared.aba` on NumPy arrays) against the same
batch in Rust (`python/examples/aba_batch.rs`, `lsdc::api::StateBatch`, linked with the very build
of lsdc the extension links), in interleaved rounds: thread
CPU time of the Python call (argument conversion, the Rust loop, the result array) and of the
Rust loop alone, best and median, and the accelerations compared bit for bit.

    (cd python && CARGO_TARGET_DIR=../target/python cargo build --release --locked --example aba_batch)
    python bench/python_aba.py [--rounds 15] [--states 10000] [--program examples/double_pendulum.lsd]

(with the `lsdc` package installed: tools/python-tests, or `pip install .` in python/).
"""

import argparse
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import lsdc

ROOT = pathlib.Path(__file__).resolve().parents[1]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--states", type=int, default=10_000)
    parser.add_argument("--program", default=str(ROOT / "examples" / "double_pendulum.lsd"))
    parser.add_argument("--rust", default=str(ROOT / "target" / "python" / "release" / "examples" / "aba_batch"))
    args = parser.parse_args()

    prepared = lsdc.load(args.program).prepare()
    generator = np.random.default_rng(52)
    q = generator.uniform(-np.pi, np.pi, (args.states, prepared.nq))
    v = generator.uniform(-2, 2, (args.states, prepared.nv))
    tau = generator.uniform(-5, 5, (args.states, prepared.nv))
    with tempfile.TemporaryDirectory() as scratch:
        states = pathlib.Path(scratch) / "states.f64"
        out = pathlib.Path(scratch) / "a.f64"
        states.write_bytes(np.concatenate([q.ravel(), v.ravel(), tau.ravel()]).astype("<f8").tobytes())
        python_times, rust_times = [], []
        for _ in range(args.rounds):
            started = time.thread_time()
            a = prepared.aba(q, v, tau)
            python_times.append(time.thread_time() - started)
            done = subprocess.run([args.rust, args.program, states, out], capture_output=True,
                                  text=True, check=True)
            rust_times.append(float(done.stdout))
        from_rust = np.frombuffer(out.read_bytes(), dtype="<f8").reshape(a.shape)
    same = np.array_equal(a, from_rust)
    ratio_best = min(python_times) / min(rust_times)
    ratio_median = statistics.median(python_times) / statistics.median(rust_times)
    print(f"{args.states} states of {pathlib.Path(args.program).name}, {args.rounds} rounds")
    print(f"python Prepared.aba: best {min(python_times) * 1e3:.3f} ms, median {statistics.median(python_times) * 1e3:.3f} ms")
    print(f"rust StateBatch::aba: best {min(rust_times) * 1e3:.3f} ms, median {statistics.median(rust_times) * 1e3:.3f} ms")
    print(f"ratio python / rust: best {ratio_best:.3f}, median {ratio_median:.3f}")
    print(f"accelerations equal bit for bit: {same}")


if __name__ == "__main__":
    main()

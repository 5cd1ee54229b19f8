# %% [markdown]
# # lsdc from Python: a tour
#
# A notebook-style script (cells marked `# %%`, as Jupyter's and VS Code's "percent" format
# reads them): the double pendulum of `examples/double_pendulum.lsd` loaded, checked,
# simulated, stepped under a controller, evaluated on NumPy arrays, linearised and swept.
# Run it from this folder with `python tour.py` once the package is installed
# (`pip install .` in `python/`).

# %%
import pathlib

import numpy as np

import lsdc

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
program = lsdc.load(EXAMPLES / "double_pendulum.lsd")
print("errors:", [str(d) for d in program.diagnostics if d.is_error])

# %% [markdown]
# ## A whole run: columns of NumPy arrays, as `lsdc simulate` writes its CSV

# %%
columns = program.simulate(duration=2.0, every=0.5)
for name in ("time", "shoulder.q", "elbow.q", "kinetic_energy", "potential_energy"):
    print(f"{name:>17}", np.array2string(columns[name], precision=4))
energy = columns["kinetic_energy"] + columns["potential_energy"]
print("energy drift over the run:", energy.max() - energy.min())
try:
    print(columns.to_pandas().head())
except ImportError:
    print("(pandas is not installed: columns.to_pandas() needs it)")

# %% [markdown]
# ## A run stepped from Python: a PD law on the shoulder, sampled every 10 ms

# %%
prepared = program.prepare(duration=5.0)
simulation = prepared.simulation(["shoulder.q", "elbow.q"])
for k in range(1, 501):
    q, v = simulation.coordinates()
    simulation.set_inputs(-40.0 * q - 8.0 * v)
    simulation.advance_to(k * 0.01)
q, v = simulation.coordinates()
print(f"after {simulation.time} s under the PD law: q = {q}, q' = {v}")

# %% [markdown]
# ## The dynamics on arrays: 10,000 states in one call, evaluated in Rust

# %%
generator = np.random.default_rng(0)
q = generator.uniform(-np.pi, np.pi, (10_000, 2))
v = generator.uniform(-2, 2, (10_000, 2))
tau = generator.uniform(-5, 5, (10_000, 2))
a = prepared.aba(q, v, tau)
print("ABA:", a.shape, "RNEA gives back tau:", np.abs(prepared.rnea(q, v, a) - tau).max())
print("mass matrix at the first state:\n", prepared.crba(q[0]))
print("the lower rod's Jacobian (its frame, angular then linear):\n", prepared.jacobian(q[0], "lower"))

# %% [markdown]
# ## The linear model at rest at the initial angles (held by the inputs), and a sweep

# %%
held = program.linearize(inputs=["shoulder.q", "elbow.q"], equilibrium=True)
print("states:", held["states"])
print("eigenvalues:", np.round(held["eigenvalues"], 4))

table = program.sweep(grid={"shoulder.q": (0.1, 1.0, 4)}, duration=1.0)
runs = table.columns()
print("sweep:", list(zip(runs["shoulder.q"], runs["status"], runs["max(kinetic_energy)"])))

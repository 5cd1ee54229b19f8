//! The shared library inside the FMI units of `lsdc export-fmu`: the FMI 3.0 co-simulation and
//! model-exchange functions (`fmi3*`, the standard's `fmi3Functions.h`) and the FMI 2.0 ones (`fmi2*`,
//! `fmi2Functions.h`), exported unprefixed, so that one library serves both versions. At
//! instantiation it reads the unit's `resources/lsdc/unit.json` and the program beside it; at
//! the end of initialisation it prepares the program with the parameters' values and starts a
//! `Simulator` with the inputs; each communication step holds the inputs and advances the run
//! to the step's end with the program's own integrator, events and loop projection.
//!
//! In model exchange (units of trees without events) the importer sets the time and the
//! continuous states, the declared coordinates and their rates, and reads their derivatives
//! from the program's equations. The optional capabilities (saved states, directional
//! derivatives, scheduled execution) are not provided: their functions exist, as every importer
//! loads them, and return an error that says so.

mod fmi2;
mod fmi3;
mod instance;
mod log;
mod unit;

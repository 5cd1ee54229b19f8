//! Simulation samples as one JSON document, written when the run ends: the simulation's
//! serialised form, with the frames asked for by name (`--output-frame`) taken out of the
//! outputs into each sample's `frames`, by name.

use std::io::{self, Write};

use serde_json::{Map, Value};

use super::sample_writer::SampleWriter;
use crate::kinematics::frames::{FrameState, STATE_COMPONENTS};
use crate::simulate::run::{Sample, Simulation};

/// Writes the simulation as JSON when the run is over.
pub struct JsonWriter<W: Write> {
    out: W,
    frame_names: Vec<String>,
}

impl<W: Write> JsonWriter<W> {
    /// `frame_names`: the frames whose 13 columns end the outputs, in order.
    pub fn new(out: W, frame_names: &[String]) -> Self {
        JsonWriter {
            out,
            frame_names: frame_names.to_vec(),
        }
    }

    /// The document: the simulation, each sample with `frames` when frames were asked for.
    fn document(&self, simulation: &Simulation) -> Value {
        let mut value = serde_json::to_value(simulation).unwrap_or_default();
        if self.frame_names.is_empty() {
            return value;
        }
        let frame_columns = STATE_COMPONENTS.len() * self.frame_names.len();
        let declared = simulation.output_names.len() - frame_columns;
        set_or_remove(&mut value, "output_names", |names| names.truncate(declared));
        let samples = value["samples"].as_array_mut().into_iter().flatten();
        for (json_sample, sample) in samples.zip(&simulation.samples) {
            set_or_remove(json_sample, "outputs", |outputs| outputs.truncate(declared));
            let states = sample.outputs[declared..].chunks(STATE_COMPONENTS.len());
            let by_name: Map<String, Value> = (self.frame_names.iter().zip(states))
                .map(|(name, values)| (name.clone(), serde_json::json!(frame_state(values))))
                .collect();
            json_sample["frames"] = Value::Object(by_name);
        }
        value
    }
}

/// Shortens the array `key` of `object` by `shorten`; removes it if it ends empty (as the
/// simulation's form leaves out empty outputs).
fn set_or_remove(object: &mut Value, key: &str, shorten: impl Fn(&mut Vec<Value>)) {
    let Some(map) = object.as_object_mut() else {
        return;
    };
    if let Some(Value::Array(array)) = map.get_mut(key) {
        shorten(array);
        if array.is_empty() {
            map.remove(key);
        }
    }
}

/// A frame's state from its 13 columns, in `STATE_COMPONENTS` order.
fn frame_state(values: &[f64]) -> FrameState {
    let part = |range: std::ops::Range<usize>| values[range].to_vec();
    let three = |range| <[f64; 3]>::try_from(part(range)).unwrap_or_default();
    FrameState {
        position: three(0..3),
        orientation: <[f64; 4]>::try_from(part(3..7)).unwrap_or_default(),
        velocity: three(7..10),
        angular_velocity: three(10..13),
    }
}

impl<W: Write> SampleWriter for JsonWriter<W> {
    /// Nothing before the end: the document is the simulation, which keeps its samples.
    fn write_sample(&mut self, _sample: &Sample) {}

    fn finish(mut self: Box<Self>, simulation: &Simulation) -> io::Result<()> {
        let document = self.document(simulation);
        let text = serde_json::to_string_pretty(&document).unwrap_or_default() + "\n";
        self.out.write_all(text.as_bytes())?;
        self.out.flush()
    }

    fn needs_kept_samples(&self) -> bool {
        true
    }
}

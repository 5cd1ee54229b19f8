//! The journal of a sweep writing to a file: `FILE.journal` beside it, one line per finished
//! run, appended and flushed as each run finishes, so that a sweep interrupted (a signal, a
//! run limit, a killed process) is resumed (`--resume`) without doing its finished runs
//! again (the lines reach the operating system as each run ends: a process killed loses no
//! finished run; a machine that loses power may lose the last ones). When the sweep is complete its file is written from the journal and the journal is
//! removed.
//!
//! The first line names the sweep (`fingerprint`: the design, the columns, the settings and the
//! shard), so that a journal is never resumed into another sweep. Each further line is one
//! run's record as JSON, its numbers as the bits of their `f64` (so that they come back
//! exactly, NaN included). A last line cut short by the interruption is ignored: that run is
//! done again.

use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::record::{RunRecord, Status};

/// The journal's path beside the sweep's output file.
pub fn path_for(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".journal");
    PathBuf::from(name)
}

/// A digest of the sweep's description: `std`'s SipHash with its fixed keys, the same in every
/// process of one build of lsdc (another build may give another digest: its journal is then
/// refused, never misread).
pub fn digest(bytes: &[u8]) -> u64 {
    use std::hash::{DefaultHasher, Hasher};
    let mut hasher = DefaultHasher::new();
    hasher.write(bytes);
    hasher.finish()
}

#[derive(Serialize, Deserialize)]
struct Header {
    sweep: String,
}

/// A record as a journal line: numbers as the bits of their `f64`.
#[derive(Serialize, Deserialize)]
struct Line {
    run: usize,
    values: Vec<u64>,
    status: String,
    failure_time: Option<u64>,
    failure: Option<String>,
    steps: Option<u64>,
    end_time: Option<u64>,
    end: Vec<Option<u64>>,
    min: Vec<Option<u64>>,
    max: Vec<Option<u64>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    samples: Vec<Vec<u64>>,
}

fn bits(values: &[Option<f64>]) -> Vec<Option<u64>> {
    values.iter().map(|x| x.map(f64::to_bits)).collect()
}

fn floats(values: &[Option<u64>]) -> Vec<Option<f64>> {
    values.iter().map(|x| x.map(f64::from_bits)).collect()
}

impl Line {
    fn of(record: &RunRecord) -> Line {
        Line {
            run: record.run,
            values: record.values.iter().map(|x| x.to_bits()).collect(),
            status: record.status.name().to_string(),
            failure_time: record.failure_time.map(f64::to_bits),
            failure: record.failure.clone(),
            steps: record.steps,
            end_time: record.end_time.map(f64::to_bits),
            end: bits(&record.end),
            min: bits(&record.min),
            max: bits(&record.max),
            samples: (record.samples.iter())
                .map(|s| s.iter().map(|x| x.to_bits()).collect())
                .collect(),
        }
    }

    fn record(self) -> Option<RunRecord> {
        Some(RunRecord {
            run: self.run,
            values: self.values.into_iter().map(f64::from_bits).collect(),
            status: Status::from_name(&self.status)?,
            failure_time: self.failure_time.map(f64::from_bits),
            failure: self.failure,
            steps: self.steps,
            end_time: self.end_time.map(f64::from_bits),
            end: floats(&self.end),
            min: floats(&self.min),
            max: floats(&self.max),
            samples: (self.samples.into_iter())
                .map(|s| s.into_iter().map(f64::from_bits).collect())
                .collect(),
        })
    }
}

/// An open journal, appended to as runs finish.
pub struct Journal {
    file: File,
    path: PathBuf,
}

impl Journal {
    /// Starts a new journal for the sweep `fingerprint` (an older one is replaced).
    pub fn create(path: &Path, fingerprint: &str) -> Result<Journal, String> {
        let mut file = File::create(path).map_err(|e| cannot("write", path, e))?;
        let header = serde_json::to_string(&Header {
            sweep: fingerprint.to_string(),
        })
        .map_err(|e| e.to_string())?;
        writeln!(file, "{header}").map_err(|e| cannot("write", path, e))?;
        file.sync_data().map_err(|e| cannot("write", path, e))?;
        Ok(Journal {
            file,
            path: path.to_path_buf(),
        })
    }

    /// Opens the journal of an interrupted sweep to go on with it: its finished runs by
    /// index. An error when it is missing or of another sweep.
    pub fn resume(
        path: &Path,
        fingerprint: &str,
    ) -> Result<(Journal, BTreeMap<usize, RunRecord>), String> {
        let text = std::fs::read_to_string(path).map_err(|e| cannot("read", path, e))?;
        let mut lines = text.split_inclusive('\n');
        let header: Option<Header> = lines.next().and_then(|l| serde_json::from_str(l).ok());
        match header {
            Some(header) if header.sweep == fingerprint => {}
            Some(_) => {
                return Err(format!(
                    "`{}` is the journal of another sweep (another program, design, settings or shard); remove it, or run without --resume to start again",
                    path.display()
                ))
            }
            None => return Err(format!("`{}` is not a sweep's journal", path.display())),
        }
        let mut finished = BTreeMap::new();
        // The bytes of the header and of the records read so far.
        let mut offset = text.find('\n').map_or(text.len(), |i| i + 1);
        for line in lines {
            // A line without its end, or one that does not read, was cut by the interruption:
            // the journal goes on from before it.
            let record = (line.ends_with('\n'))
                .then(|| serde_json::from_str::<Line>(line).ok())
                .flatten()
                .and_then(Line::record);
            match record {
                Some(record) => {
                    finished.insert(record.run, record);
                    offset += line.len();
                }
                None => break,
            }
        }
        let file = OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| cannot("write", path, e))?;
        file.set_len(offset as u64)
            .map_err(|e| cannot("write", path, e))?;
        let mut journal = Journal {
            file,
            path: path.to_path_buf(),
        };
        use std::io::Seek;
        (journal.file.seek(std::io::SeekFrom::End(0))).map_err(|e| cannot("write", path, e))?;
        Ok((journal, finished))
    }

    /// Appends a finished run, on disk before this returns.
    pub fn append(&mut self, record: &RunRecord) -> Result<(), String> {
        let line = serde_json::to_string(&Line::of(record)).map_err(|e| e.to_string())?;
        let path = &self.path;
        // One write per line, straight to the operating system (no buffer of ours): a process
        // that ends leaves at most the last line cut. No `sync` per run: a thousand runs a
        // second would wait on the disk.
        (self.file.write_all(format!("{line}\n").as_bytes())).map_err(|e| cannot("write", path, e))
    }

    /// Removes the journal of a complete sweep.
    pub fn remove(self) -> Result<(), String> {
        std::fs::remove_file(&self.path).map_err(|e| cannot("remove", &self.path, e))
    }
}

fn cannot(what: &str, path: &Path, error: std::io::Error) -> String {
    format!("cannot {what} `{}`: {error}", path.display())
}

//! The runs of a sweep, each a value for every varied name: a grid (`NAME=a:b:n` axes, the
//! first axis slowest, as nested loops in the order given), a list read from a CSV file (a
//! column per name, a row per run), or a sample of stated distributions over the points of a
//! design of the unit cube:
//!
//! - Monte Carlo: independent uniform points from ChaCha12 seeded by `--seed` (`rand`'s
//!   `StdRng`);
//! - Latin hypercube (McKay, Beckman & Conover, "A comparison of three methods for selecting
//!   values of input variables in the analysis of output from a computer code",
//!   Technometrics 21, 1979): each axis cut in n equal strata, one point in each, the strata
//!   of the axes paired by independent random permutations;
//! - Sobol (Sobol' 1967), the `sobol_burley` crate: Joe & Kuo's direction numbers ("Constructing
//!   Sobol sequences with better two-dimensional projections", SIAM J. Sci. Comput. 30, 2008),
//!   Owen-scrambled by Burley's hash ("Practical hash-based Owen scrambling", JCGT 9, 2020)
//!   seeded by `--seed`; a maintained crate rather than a copy of the direction-number table.
//!   Its points have 24 bits (f32) — design points, not the values' precision: each is taken
//!   at the centre of its cell of width 2⁻²⁴. At most 2¹⁶ points and 256 names.
//!
//! A design is made whole, in one thread, before any run: every shard and every thread count
//! sees the same runs.

use rand::seq::SliceRandom;
use rand::{Rng, RngExt, SeedableRng};

use super::distribution::Distribution;

/// Every run's values: `runs[i][j]` is the value of `names[j]` in run i.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    pub names: Vec<String>,
    pub runs: Vec<Vec<f64>>,
}

/// One axis of a grid: `count` values evenly spaced from `from` to `to`, both included.
#[derive(Clone, Debug, PartialEq)]
pub struct GridAxis {
    pub name: String,
    pub from: f64,
    pub to: f64,
    pub count: usize,
}

impl GridAxis {
    /// Reads `NAME=a:b:n`.
    pub fn parse(text: &str) -> Result<GridAxis, String> {
        let form =
            || format!("`--grid {text}`: write NAME=FROM:TO:COUNT, for example `arm.q=0:1.5:16`");
        let (name, range) = text.rsplit_once('=').ok_or_else(form)?;
        let parts: Vec<&str> = range.split(':').collect();
        let [from, to, count] = parts[..] else {
            return Err(form());
        };
        let number = |s: &str| {
            (s.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
                .ok_or_else(|| format!("`--grid {text}`: `{s}` is not a finite number"))
        };
        let count: usize = count
            .trim()
            .parse()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| {
                format!("`--grid {text}`: `{count}` is not a count of values (1 or more)")
            })?;
        if name.trim().is_empty() {
            return Err(form());
        }
        Ok(GridAxis {
            name: name.trim().to_string(),
            from: number(from)?,
            to: number(to)?,
            count,
        })
    }

    /// The axis's values, `from` and `to` exactly.
    fn values(&self) -> Vec<f64> {
        let last = self.count.saturating_sub(1).max(1) as f64;
        (0..self.count)
            .map(|k| match k + 1 == self.count && self.count > 1 {
                true => self.to,
                false => self.from + (self.to - self.from) * (k as f64 / last),
            })
            .collect()
    }
}

/// The grid of `axes`: every combination, the first axis varying slowest.
pub fn grid(axes: &[GridAxis]) -> Design {
    let mut runs = vec![Vec::new()];
    for axis in axes {
        let values = axis.values();
        runs = (runs.iter())
            .flat_map(|run| {
                values.iter().map(move |&v| {
                    let mut run = run.clone();
                    run.push(v);
                    run
                })
            })
            .collect();
    }
    Design {
        names: axes.iter().map(|a| a.name.clone()).collect(),
        runs,
    }
}

/// Where and why a list of runs cannot be read: `line` and `column` count from 1.
#[derive(Clone, Debug, PartialEq)]
pub struct ListError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// The runs of a CSV text: a header of names, then a row of numbers per run (blank lines and
/// lines starting with `#` are skipped).
pub fn list(text: &str) -> Result<Design, ListError> {
    let mut lines = (text.lines().enumerate())
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err(ListError {
            line: 1,
            column: 1,
            message: "no header: the first line names the columns (`arm.q,k`)".to_string(),
        });
    };
    let names: Vec<String> = header.split(',').map(|n| n.trim().to_string()).collect();
    for (index, name) in names.iter().enumerate() {
        let earlier = names[..index].iter().position(|n| n == name);
        if name.is_empty() || earlier.is_some() {
            let what = match name.is_empty() {
                true => "an empty name".to_string(),
                false => format!("`{name}` named twice"),
            };
            return Err(ListError {
                line: header_line + 1,
                column: field_column(header, index),
                message: format!("{what} in the header"),
            });
        }
    }
    let mut runs = Vec::new();
    for (line_index, line) in lines {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != names.len() {
            return Err(ListError {
                line: line_index + 1,
                column: 1,
                message: format!(
                    "{} values for {} names in the header",
                    fields.len(),
                    names.len()
                ),
            });
        }
        let mut run = Vec::with_capacity(fields.len());
        for (index, field) in fields.iter().enumerate() {
            match field.trim().parse::<f64>().ok().filter(|x| x.is_finite()) {
                Some(value) => run.push(value),
                None => {
                    return Err(ListError {
                        line: line_index + 1,
                        column: field_column(line, index),
                        message: format!(
                            "`{}` is not a finite number (for `{}`)",
                            field.trim(),
                            names[index]
                        ),
                    })
                }
            }
        }
        runs.push(run);
    }
    Ok(Design { names, runs })
}

/// The column (from 1, in characters) where the `index`-th comma-separated field starts.
fn field_column(line: &str, index: usize) -> usize {
    let before: usize = (line.split(',').take(index))
        .map(|f| f.chars().count() + 1)
        .sum();
    let field = line.split(',').nth(index).unwrap_or("");
    before + (field.chars().count() - field.trim_start().chars().count()) + 1
}

/// How the points of a sample cover the unit cube.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    MonteCarlo,
    LatinHypercube,
    Sobol,
}

/// The most points and names of a Sobol design (`sobol_burley`'s limits).
pub const SOBOL_MOST_POINTS: usize = 1 << 16;
pub const SOBOL_MOST_NAMES: usize = 256;

/// `count` runs of the `variables`' distributions over a design of the unit cube, reproducible
/// from `seed`.
pub fn sample(
    variables: &[(String, Distribution)],
    count: usize,
    sampling: Sampling,
    seed: u64,
) -> Result<Design, String> {
    let dimensions = variables.len();
    let points = match sampling {
        Sampling::MonteCarlo => monte_carlo(count, dimensions, seed),
        Sampling::LatinHypercube => latin_hypercube(count, dimensions, seed),
        Sampling::Sobol => sobol(count, dimensions, seed)?,
    };
    let runs = (points.iter())
        .map(|point| {
            (point.iter().zip(variables))
                .map(|(&u, (_, distribution))| distribution.quantile(u))
                .collect()
        })
        .collect();
    Ok(Design {
        names: variables.iter().map(|(n, _)| n.clone()).collect(),
        runs,
    })
}

/// A uniform number in (0, 1), never 0 or 1: 53 random bits taken at the centre of their cell.
fn open_unit(rng: &mut impl Rng) -> f64 {
    ((rng.next_u64() >> 11) as f64 + 0.5) * (1.0 / (1u64 << 53) as f64)
}

fn monte_carlo(count: usize, dimensions: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..count)
        .map(|_| (0..dimensions).map(|_| open_unit(&mut rng)).collect())
        .collect()
}

fn latin_hypercube(count: usize, dimensions: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut points = vec![vec![0.0; dimensions]; count];
    for axis in 0..dimensions {
        let mut strata: Vec<usize> = (0..count).collect();
        strata.shuffle(&mut rng);
        for (point, stratum) in points.iter_mut().zip(strata) {
            let within: f64 = rng.random::<f64>();
            // In the stratum's open interval: `within` may be 0, never 1.
            let u = (stratum as f64 + within) / count as f64;
            point[axis] = u.max(0.5 / (count as f64 * (1u64 << 53) as f64));
        }
    }
    points
}

fn sobol(count: usize, dimensions: usize, seed: u64) -> Result<Vec<Vec<f64>>, String> {
    if count > SOBOL_MOST_POINTS {
        return Err(format!(
            "a Sobol design has at most {SOBOL_MOST_POINTS} points; {count} asked for"
        ));
    }
    if dimensions > SOBOL_MOST_NAMES {
        return Err(format!(
            "a Sobol design has at most {SOBOL_MOST_NAMES} names; {dimensions} given"
        ));
    }
    // The crate's seed is 32 bits: both halves of `--seed` are folded into it.
    let seed = (seed as u32) ^ ((seed >> 32) as u32);
    let cell = 1.0 / (1u64 << 24) as f64;
    Ok((0..count as u32)
        .map(|index| {
            (0..dimensions as u32)
                .map(|axis| {
                    let u = sobol_burley::sample(index, axis, seed) as f64;
                    ((u / cell).floor() + 0.5) * cell
                })
                .collect()
        })
        .collect())
}

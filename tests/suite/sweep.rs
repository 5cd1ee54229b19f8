//! `lsdc sweep`: the designs (grid, list, samples) against their definitions, each run's row
//! against `lsdc simulate` of the same values, results independent of the thread count, shards
//! gathered and interrupted sweeps resumed equal to the whole sweep bit for bit, Parquet read
//! back by the `parquet` crate's own reader, failures kept to their run.

use std::path::{Path, PathBuf};

use lsdc::studies::sweep::design::{self, GridAxis, Sampling};
use lsdc::studies::sweep::distribution::{
    standard_normal_cdf, standard_normal_quantile, Distribution,
};
use lsdc::studies::sweep::Shard;

use crate::common::lsdc;

/// A fresh directory for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

#[test]
fn normal_quantile_meets_published_values_and_inverts_the_cdf() {
    // Published percentage points of the standard normal (Abramowitz & Stegun, table 26.5;
    // Wichura 1988, table 1).
    let points = [
        (0.975, 1.959_963_984_540_054),
        (0.5, 0.0),
        (0.841_344_746_068_542_9, 1.0),
        (1e-10, -6.361_340_902_404_056),
        (0.999, 3.090_232_306_167_813_6),
    ];
    for (p, z) in points {
        let q = standard_normal_quantile(p);
        assert!(
            (q - z).abs() <= 1e-14 * z.abs().max(1.0),
            "Φ⁻¹({p}) = {q}, not {z}"
        );
    }
    // Two independent algorithms: AS 241 against the CDF through libm's erfc.
    for k in 1..1000 {
        let p = k as f64 / 1000.0;
        let back = standard_normal_cdf(standard_normal_quantile(p));
        assert!((back - p).abs() <= 2e-16 * 8.0, "Φ(Φ⁻¹({p})) = {back}");
    }
    let truncated = Distribution::parse("truncnormal(1, 2, 0.5, 1.5)").expect("reads");
    for u in [1e-9, 0.3, 0.999_999] {
        let x = truncated.quantile(u);
        assert!((0.5..=1.5).contains(&x), "{x} outside the truncation");
    }
    // The truncated normal's median: the point splitting its mass in two.
    let median = truncated.quantile(0.5);
    let mass = |x: f64| standard_normal_cdf((x - 1.0) / 2.0);
    assert!((mass(median) - mass(0.5) - (mass(1.5) - mass(median))).abs() < 1e-15);
    for bad in [
        "normal(0, -1)",
        "uniform(2, 1)",
        "gamma(1, 2)",
        "normal(1)",
        "normal(a, 1)",
    ] {
        assert!(Distribution::parse(bad).is_err(), "`{bad}` read");
    }
}

#[test]
fn grid_is_every_combination_first_axis_slowest_ends_exact() {
    let axes = [
        GridAxis::parse("a=0:1:3").expect("axis"),
        GridAxis::parse("b=0.1:0.3:2").expect("axis"),
    ];
    let grid = design::grid(&axes);
    assert_eq!(grid.names, ["a", "b"]);
    let expected = [
        [0.0, 0.1],
        [0.0, 0.3],
        [0.5, 0.1],
        [0.5, 0.3],
        [1.0, 0.1],
        [1.0, 0.3],
    ];
    assert_eq!(grid.runs, expected.map(|r| r.to_vec()).to_vec());
    for bad in ["a=0:1", "a=0:1:0", "=0:1:3", "a=x:1:3"] {
        assert!(GridAxis::parse(bad).is_err(), "`{bad}` read");
    }
}

#[test]
fn list_reads_runs_and_locates_its_errors() {
    let list = design::list("# a comment\nk, swing.q\n1, 0.5\n\n2,0.25\n").expect("reads");
    assert_eq!(list.names, ["k", "swing.q"]);
    assert_eq!(list.runs, vec![vec![1.0, 0.5], vec![2.0, 0.25]]);
    let error = design::list("k,q\n1,2\n3, x\n").expect_err("x is no number");
    assert_eq!((error.line, error.column), (3, 4), "{error:?}");
    assert!(error.message.contains("`x`") && error.message.contains("`q`"));
    let error = design::list("k,q\n1\n").expect_err("a value is missing");
    assert_eq!(error.line, 2);
    let error = design::list("k,k\n").expect_err("a name twice");
    assert_eq!((error.line, error.column), (1, 3));
}

/// The index of the stratum of `u` among `n` equal ones.
fn stratum(u: f64, n: usize) -> usize {
    (u * n as f64) as usize
}

#[test]
fn samples_cover_the_unit_cube_as_their_designs_promise() {
    let uniform = |name: &str| {
        (
            name.to_string(),
            Distribution::Uniform {
                low: 0.0,
                high: 1.0,
            },
        )
    };
    let variables = [uniform("a"), uniform("b"), uniform("c")];
    // Latin hypercube: on every axis, exactly one point in each of the n strata.
    let n = 50;
    let latin = design::sample(&variables, n, Sampling::LatinHypercube, 7).expect("design");
    for axis in 0..3 {
        let mut strata: Vec<usize> = latin.runs.iter().map(|r| stratum(r[axis], n)).collect();
        strata.sort();
        assert_eq!(strata, (0..n).collect::<Vec<_>>(), "axis {axis}");
    }
    // Sobol: the first 2^m points are a (0, m, 1)-net on each axis: one per stratum of 2^-m.
    let n = 64;
    let sobol = design::sample(&variables, n, Sampling::Sobol, 3).expect("design");
    for axis in 0..3 {
        let mut strata: Vec<usize> = sobol.runs.iter().map(|r| stratum(r[axis], n)).collect();
        strata.sort();
        assert_eq!(strata, (0..n).collect::<Vec<_>>(), "axis {axis}");
    }
    assert!(design::sample(&variables, (1 << 16) + 1, Sampling::Sobol, 0).is_err());
    // Monte Carlo: reproducible from its seed, different for another; the mean of 4000
    // uniform draws within 4 standard errors (1/sqrt(12 n)) of 1/2.
    let draw = |seed| design::sample(&variables, 4000, Sampling::MonteCarlo, seed).expect("design");
    let (first, again, other) = (draw(11), draw(11), draw(12));
    assert_eq!(first, again);
    assert_ne!(first, other);
    let mean = first.runs.iter().map(|r| r[1]).sum::<f64>() / 4000.0;
    assert!(
        (mean - 0.5).abs() < 4.0 / (12.0f64 * 4000.0).sqrt(),
        "mean {mean}"
    );
    // Every value strictly inside (0, 1): a normal's quantile is finite there.
    let normal = [("x".to_string(), Distribution::Normal { mean: 0.0, sd: 1.0 })];
    for sampling in [
        Sampling::MonteCarlo,
        Sampling::LatinHypercube,
        Sampling::Sobol,
    ] {
        let design = design::sample(&normal, 256, sampling, 5).expect("design");
        assert!(design.runs.iter().all(|r| r[0].is_finite()));
    }
}

#[test]
fn shards_split_the_runs_contiguously_and_completely() {
    for total in [0, 1, 7, 10, 1001] {
        for count in [1, 3, 4] {
            let mut next = 0;
            for index in 1..=count {
                let runs = Shard { index, count }.runs(total);
                assert_eq!(runs.start, next);
                next = runs.end;
            }
            assert_eq!(next, total);
        }
    }
    assert_eq!(Shard::parse("0/4", true), Ok(Shard { index: 1, count: 4 }));
    for bad in ["0/4", "5/4", "1", "a/b"] {
        assert!(Shard::parse(bad, false).is_err(), "`{bad}` read");
    }
}

/// The values of the CSV column `name` (empty cells as NaN).
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    lines
        .map(|l| {
            l.split(',')
                .nth(k)
                .expect("field")
                .parse()
                .unwrap_or(f64::NAN)
        })
        .collect()
}

#[test]
fn each_row_is_the_run_simulate_gives_for_its_values() {
    let dir = scratch("rows");
    let out = path(&dir, "runs.csv");
    let (code, _, stderr) = lsdc(&[
        "sweep",
        "examples/pendulum.lsd",
        "--grid",
        "swing.q=0.2:1.4:4",
        "--grid",
        "swing.q'=-1:1:2",
        "--duration",
        "1",
        "-o",
        &out,
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("8 of 8 runs: 8 ok"), "{stderr}");
    let csv = std::fs::read_to_string(&out).expect("written");
    let angles = column(&csv, "swing.q");
    let rates = column(&csv, "swing.q'");
    let ends = column(&csv, "end(swing.q)");
    let minima = column(&csv, "min(swing.q)");
    let maxima = column(&csv, "max(swing.q)");
    assert_eq!(
        column(&csv, "run"),
        (0..8).map(f64::from).collect::<Vec<_>>()
    );
    let pendulum = std::fs::read_to_string("examples/pendulum.lsd").expect("example");
    for run in [0, 5, 7] {
        // The same run by `lsdc simulate`: the program with this run's initial values.
        let program = pendulum.replace(
            "initial swing.q = pi / 3 ;",
            &format!(
                "initial swing.q = {:e}, swing.q' = {:e} ;",
                angles[run], rates[run]
            ),
        );
        assert_ne!(program, pendulum, "the example's initial line moved");
        let file = dir.join(format!("run{run}.lsd"));
        std::fs::write(&file, program).expect("written");
        let (code, samples, stderr) =
            lsdc(&["simulate", &file.display().to_string(), "--duration", "1"]);
        assert_eq!(code, 0, "{stderr}");
        let angle = column(&samples, "swing.q");
        let last = *angle.last().expect("samples");
        assert!(
            (last - ends[run]).abs() <= 1e-12,
            "run {run}: {last} against {}",
            ends[run]
        );
        let lowest = angle.iter().copied().fold(f64::INFINITY, f64::min);
        let highest = angle.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!((lowest - minima[run]).abs() <= 1e-12 && (highest - maxima[run]).abs() <= 1e-12);
    }
    // Energy is conserved in every run: the pendulum's closed form at the start (kinetic
    // ½ I ω², potential −m g l_c cos q with I about the pivot = 0.1 + 1.2·0.5²) equals the
    // end's.
    let kinetic = column(&csv, "end(kinetic_energy)");
    let potential = column(&csv, "end(potential_energy)");
    let inertia = 0.1 + 1.2 * 0.25;
    for run in 0..8 {
        let start = 0.5 * inertia * rates[run].powi(2) - 1.2 * 9.81 * 0.5 * angles[run].cos();
        let end = kinetic[run] + potential[run];
        assert!(
            (end - start).abs() < 1e-8,
            "run {run}: energy {end} against {start}"
        );
    }
}

/// Runs `lsdc sweep` with `args`, expecting success.
fn sweep(args: &[&str]) -> String {
    let (code, _, stderr) = lsdc(&[&["sweep"], args].concat());
    assert_eq!(code, 0, "{args:?}: {stderr}");
    stderr
}

/// The sweep every test of shards and resumption compares with: a Latin hypercube of the
/// double pendulum's two initial angles and a value of the program.
const SAMPLE: [&str; 10] = [
    "examples/double_pendulum.lsd",
    "--vary",
    "shoulder.q=uniform(0.5, 2.5)",
    "--vary",
    "elbow.q=normal(-1, 0.3)",
    "--sample",
    "24",
    "--design",
    "latin",
    "--duration=0.5",
];

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let dir = scratch("threads");
    for (name, jobs) in [("one", "1"), ("two", "2")] {
        let csv = path(&dir, &format!("{name}.csv"));
        let parquet = path(&dir, &format!("{name}.parquet"));
        sweep(
            &[
                &SAMPLE[..],
                &[
                    "-j",
                    jobs,
                    "-o",
                    &csv,
                    "--samples",
                    &path(&dir, &format!("{name}.samples.csv")),
                ],
            ]
            .concat(),
        );
        sweep(&[&SAMPLE[..], &["-j", jobs, "-o", &parquet]].concat());
    }
    for file in ["{}.csv", "{}.parquet", "{}.samples.csv"] {
        let read = |name: &str| std::fs::read(dir.join(file.replace("{}", name))).expect("written");
        assert!(
            read("one") == read("two"),
            "{file} differs between 1 and 2 threads"
        );
    }
}

#[test]
fn four_shards_gathered_equal_the_whole_sweep_bit_for_bit() {
    let dir = scratch("shards");
    for extension in ["csv", "parquet"] {
        let whole = path(&dir, &format!("whole.{extension}"));
        let whole_samples = path(&dir, &format!("whole.samples.{extension}"));
        sweep(&[&SAMPLE[..], &["-o", &whole, "--samples", &whole_samples]].concat());
        let mut parts = Vec::new();
        let mut sample_parts = Vec::new();
        // The parts in another order than their indices: gather sorts by run.
        for k in [3, 1, 4, 2] {
            let part = path(&dir, &format!("part{k}.{extension}"));
            let samples = path(&dir, &format!("part{k}.samples.{extension}"));
            let shard = format!("{k}/4");
            let stderr = sweep(
                &[
                    &SAMPLE[..],
                    &["--shard", &shard, "-o", &part, "--samples", &samples],
                ]
                .concat(),
            );
            assert!(stderr.contains("6 of 6 runs (runs"), "{stderr}");
            parts.push(part);
            sample_parts.push(samples);
        }
        for (parts, whole, name) in [
            (&parts, &whole, "gathered"),
            (&sample_parts, &whole_samples, "gathered.samples"),
        ] {
            let gathered = path(&dir, &format!("{name}.{extension}"));
            let mut args = vec!["sweep", "gather"];
            args.extend(parts.iter().map(String::as_str));
            args.extend(["-o", &gathered]);
            let (code, _, stderr) = lsdc(&args);
            assert_eq!(code, 0, "{stderr}");
            let (a, b) = (
                std::fs::read(&gathered).expect("gathered"),
                std::fs::read(whole).expect("whole"),
            );
            assert!(a == b, "{gathered} differs from {whole}");
        }
        // A part given twice, or one missing, is refused.
        let twice = [
            vec!["sweep", "gather"],
            parts.iter().map(String::as_str).collect(),
            vec![&parts[0], "-o", "/dev/null"],
        ]
        .concat();
        let (code, _, stderr) = lsdc(&twice);
        assert!(
            code == 2 && stderr.contains("the same shard given twice"),
            "{stderr}"
        );
        let missing = [
            vec!["sweep", "gather"],
            parts[1..].iter().map(String::as_str).collect(),
            vec!["-o", "/dev/null"],
        ]
        .concat();
        let (code, _, stderr) = lsdc(&missing);
        assert!(code == 2 && stderr.contains("is in no part"), "{stderr}");
    }
}

#[test]
fn an_interrupted_sweep_resumed_equals_an_uninterrupted_one() {
    let dir = scratch("resume");
    for extension in ["csv", "parquet"] {
        let whole = path(&dir, &format!("whole.{extension}"));
        sweep(&[&SAMPLE[..], &["-o", &whole]].concat());
        let resumed = path(&dir, &format!("resumed.{extension}"));
        let journal = format!("{resumed}.journal");
        // Stopped after 5 runs: no results yet, the journal kept, exit code 3.
        let (code, _, stderr) = lsdc(
            &[
                &["sweep"],
                &SAMPLE[..],
                &["-o", &resumed, "--max-runs", "5"],
            ]
            .concat(),
        );
        assert_eq!(code, 3, "{stderr}");
        assert!(
            stderr.contains("5 of 24 runs") && stderr.contains("--resume"),
            "{stderr}"
        );
        assert!(!Path::new(&resumed).exists() && Path::new(&journal).exists());
        // A last line cut by the interruption is done again, not misread.
        let text = std::fs::read_to_string(&journal).expect("journal");
        std::fs::write(&journal, &text[..text.len() - 20]).expect("cut");
        let (code, _, stderr) = lsdc(
            &[
                &["sweep"],
                &SAMPLE[..],
                &["-o", &resumed, "--resume", "--max-runs", "7"],
            ]
            .concat(),
        );
        assert_eq!(code, 3, "{stderr}");
        assert!(
            stderr.contains("11 of 24 runs") && stderr.contains("(4 from the journal)"),
            "{stderr}"
        );
        let stderr = sweep(&[&SAMPLE[..], &["-o", &resumed, "--resume"]].concat());
        assert!(
            stderr.contains("24 of 24 runs") && stderr.contains("(11 from the journal)"),
            "{stderr}"
        );
        assert!(
            !Path::new(&journal).exists(),
            "the journal of a complete sweep is removed"
        );
        let (a, b) = (
            std::fs::read(&resumed).expect("resumed"),
            std::fs::read(&whole).expect("whole"),
        );
        assert!(a == b, "{resumed} differs from {whole}");
    }
    // The journal of another sweep is not resumed into this one.
    let out = path(&dir, "other.csv");
    let (code, _, _) = lsdc(&[&["sweep"], &SAMPLE[..], &["-o", &out, "--max-runs", "2"]].concat());
    assert_eq!(code, 3);
    let (code, _, stderr) = lsdc(
        &[
            &["sweep"],
            &SAMPLE[..],
            &["--seed", "9", "-o", &out, "--resume"],
        ]
        .concat(),
    );
    assert!(
        code == 2 && stderr.contains("the journal of another sweep"),
        "{stderr}"
    );
}

#[test]
fn parquet_reads_back_with_the_parquet_crate_as_the_csv_says() {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::Field;
    let dir = scratch("parquet");
    let (csv, parquet) = (path(&dir, "runs.csv"), path(&dir, "runs.parquet"));
    sweep(&[&SAMPLE[..], &["-o", &csv]].concat());
    sweep(&[&SAMPLE[..], &["-o", &parquet]].concat());
    let csv = std::fs::read_to_string(&csv).expect("csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let reader =
        SerializedFileReader::new(std::fs::File::open(&parquet).expect("parquet")).expect("reads");
    let names: Vec<String> = (reader
        .metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter())
    .map(|c| c.name().to_string())
    .collect();
    assert_eq!(names, header);
    let rows: Vec<_> = reader
        .get_row_iter(None)
        .expect("rows")
        .map(|r| r.expect("row"))
        .collect();
    assert_eq!(rows.len(), 24);
    for name in [
        "run",
        "shoulder.q",
        "end(elbow.q)",
        "max(kinetic_energy)",
        "steps",
    ] {
        let expected = column(&csv, name);
        for (row, value) in rows.iter().zip(expected) {
            let field = (row.get_column_iter())
                .find(|(n, _)| *n == name)
                .expect("column")
                .1;
            let read = match field {
                Field::Double(x) => *x,
                Field::Long(x) => *x as f64,
                other => panic!("{name}: {other:?}"),
            };
            assert_eq!(read.to_bits(), value.to_bits(), "{name}");
        }
    }
    let status = (rows[0].get_column_iter())
        .find(|(n, _)| *n == "status")
        .expect("status")
        .1;
    assert_eq!(status, &Field::Str("ok".to_string()));
}

#[test]
fn a_failed_run_is_its_own_row_and_the_others_go_on() {
    let dir = scratch("failures");
    // The four-bar's crank length: at 11, longer than the three other links together (ground
    // 4, coupler 3.5, rocker 3), the loop cannot close at any crank angle.
    let program = std::fs::read_to_string("examples/four_bar.lsd").expect("example");
    let program = program.replace("let l1 = 1.0 ;", "let l1 = ?s ; given l1 = 1.0 ;");
    let file = dir.join("four_bar.lsd");
    std::fs::write(&file, program).expect("written");
    let out = path(&dir, "runs.csv");
    let (code, _, stderr) = lsdc(&[
        "sweep",
        &file.display().to_string(),
        "--grid",
        "l1=0.5:11:3",
        "--duration",
        "0.2",
        "-o",
        &out,
        "--report",
        "json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stderr).expect("json");
    assert_eq!(report["ok"], 2, "{report}");
    assert_eq!(report["unprepared"], 1, "{report}");
    assert_eq!(report["failures"][0]["run"], 2, "{report}");
    let csv = std::fs::read_to_string(&out).expect("written");
    let last = csv.lines().nth(3).expect("third run");
    assert!(
        last.starts_with("2,1.1e1,unprepared,,") && last.contains("E08"),
        "{last}"
    );
    // A name that is neither a coordinate nor a value of the program is refused before any
    // run, with a suggestion.
    let (code, _, stderr) = lsdc(&[
        "sweep",
        &file.display().to_string(),
        "--grid",
        "l11=1:2:2",
        "--duration",
        "0.1",
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("l11") && stderr.contains("l1"), "{stderr}");
    // A list whose value does not read says where.
    let list = dir.join("runs.csv");
    std::fs::write(&list, "l1\n1\n1.2.3\n").expect("written");
    let (code, _, stderr) = lsdc(&[
        "sweep",
        &file.display().to_string(),
        "--values",
        &list.display().to_string(),
    ]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("runs.csv:3:1: `1.2.3` is not a finite number"),
        "{stderr}"
    );
}

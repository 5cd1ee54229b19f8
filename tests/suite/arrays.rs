//! Arrays of packages (`package P[i in a .. b]`): the same mechanism and the same numbers as the
//! program written out by hand or by a script, names addressable from outside, and their
//! instances' names on the command line.

use crate::common::lsdc;

/// The CSV of `lsdc simulate FILE --duration D ARGS...`: its header and rows, as written.
fn simulate(file: &str, duration: &str, args: &[&str]) -> (Vec<String>, Vec<Vec<String>>) {
    let mut all = vec!["simulate", file, "--duration", duration];
    all.extend_from_slice(args);
    let (code, stdout, stderr) = lsdc(&all);
    assert_eq!(code, 0, "{file}: {stderr}");
    let mut lines = stdout.lines().filter(|l| !l.starts_with('#'));
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

/// Asserts that two runs give the same numbers, bit for bit, column by column once the array
/// version's names are mapped to the written-out ones.
fn assert_same_run(arrays: &str, written: &str, rename: impl Fn(&str) -> String) {
    let (names_a, rows_a) = simulate(arrays, "0.05", &[]);
    let (names_w, rows_w) = simulate(written, "0.05", &[]);
    let renamed: Vec<String> = names_a.iter().map(|n| rename(n)).collect();
    assert_eq!(renamed, names_w, "the same coordinates in the same order");
    assert_eq!(rows_a.len(), rows_w.len());
    for (a, w) in rows_a.iter().zip(&rows_w) {
        assert_eq!(a, w, "the same numbers");
    }
}

#[test]
fn the_row_of_forty_four_bars_in_twenty_lines_is_the_generated_program() {
    let file = "examples/hard/four_bar_row_40_arrays.lsd";
    let text = std::fs::read_to_string(file).expect("the example");
    assert!(text.lines().count() <= 20, "{} lines", text.lines().count());
    // `c[3]:pivot.q` was `c3.q`; `k[3]:p.q` was `p3.q`, `k[3]:e.q` was `e3.q`.
    assert_same_run(file, "examples/hard/four_bar_row_40.lsd", |name| {
        let name = name.replace(":pivot", "");
        match name.strip_prefix("k[") {
            Some(rest) => {
                let (index, coordinate) = rest.split_once("]:").expect("k[i]:x");
                let (join, field) = coordinate.split_once('.').expect("join.q");
                format!("{join}{index}.{field}")
            }
            None => name.replace(['[', ']'], ""),
        }
    });
}

#[test]
fn the_delta_with_its_legs_written_once_is_the_delta() {
    // `leg[2]:Cp.a` was `C2p.a`.
    assert_same_run(
        "examples/delta_legs.lsd",
        "examples/delta_isir88.lsd",
        |name| {
            let Some(rest) = name.strip_prefix("leg[") else {
                return name.to_string();
            };
            let (index, rest) = rest.split_once("]:").expect("leg[i]:x");
            let (join, field) = rest.split_once('.').expect("join.q");
            let (letter, side) = join.split_at(1);
            format!("{letter}{index}{side}.{field}")
        },
    );
}

const SPRINGS: &str = "
import joints ;
package slider[i in 1 .. 3] =
  let k = ?s ;
  let block = body mass = i, inertia = [1, 1, 1], iframe = 0 end ;
  join [0, i, 0] ++ 1 @ earth and block with link(x) dof = x * [1, 0, 0], force = [-k * x, 0, 0] end as s ;
  initial s.x = 0.1 ;
end ;
given slider[1]:k = 4 ;
simulate duration = 1, output = 0.5 end ;
";

#[test]
fn instances_have_their_own_unknowns_given_or_set_by_their_names() {
    let dir = tempfile_dir();
    let file = dir.join("springs.lsd");
    std::fs::write(&file, SPRINGS).expect("writable");
    let file = file.to_str().expect("utf-8");
    let (code, _, stderr) = lsdc(&["simulate", file]);
    assert_eq!(code, 1, "two unknowns have no value: {stderr}");
    assert!(
        stderr.contains("slider[2]:k") && stderr.contains("slider[3]:k"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("slider[1]:k"),
        "given in the program: {stderr}"
    );
    let (names, rows) = simulate(
        file,
        "1",
        &["--set", "slider[2]:k=2", "--set", "slider[3]:k=3"],
    );
    // Each block oscillates at its own frequency sqrt(k / m): k / m = 4, 1 and 1.
    let at = |name: &str| names.iter().position(|n| n == name).expect(name);
    let last = rows.last().expect("samples");
    assert_eq!(last[0].parse::<f64>(), Ok(1.0));
    for (column, omega) in [
        ("slider[1]:s.x", 2.0f64),
        ("slider[2]:s.x", 1.0),
        ("slider[3]:s.x", 1.0),
    ] {
        let exact = 0.1 * omega.cos();
        let x: f64 = last[at(column)].parse().expect("a number");
        assert!((x - exact).abs() < 1e-5, "{column}: {x} vs {exact}");
    }
}

#[test]
fn nested_and_empty_arrays_elaborate() {
    let dir = tempfile_dir();
    let file = dir.join("nested.lsd");
    let program = "
import joints ;
package row[i in 1 .. 3] =
  package cell[j in 1 .. i] =
    let b = body mass = 1 end ;
    join [i, j, 0] ++ 1 @ earth and b with revolute([0, 0, 1]) ;
  end ;
end ;
package none[i in 1 .. 0] = let b = body mass = 1 end ; join earth and b with weld ; end ;
";
    std::fs::write(&file, program).expect("writable");
    let (code, stdout, stderr) = lsdc(&["check", file.to_str().expect("utf-8")]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("bodies    6"), "1 + 2 + 3 bodies: {stdout}");
    assert!(stdout.contains("row[3]:cell[2]:b"), "{stdout}");
}

fn tempfile_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-arrays-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    dir
}

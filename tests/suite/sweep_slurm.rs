//! A sweep run as a Slurm job array (docs/commands.md, "Sweeps on a cluster"): four array
//! tasks each run their shard, `lsdc sweep gather` merges the parts, and the result equals the
//! unsharded sweep bit for bit. Needs a running Slurm (`tools/install-slurm` installs and
//! starts a single-node one from Debian's packages); without one the test says SKIPPED, and
//! fails where `CI` is set.

use std::process::Command;

use crate::common::{lsdc, skip};

/// Whether a Slurm controller answers and a node can take jobs.
fn slurm_is_up() -> bool {
    let answers = |program: &str, args: &[&str], expected: &str| {
        (Command::new(program).args(args).output()).is_ok_and(|o| {
            o.status.success() && String::from_utf8_lossy(&o.stdout).contains(expected)
        })
    };
    answers("scontrol", &["ping"], "UP") && answers("sinfo", &["-h", "-o", "%T"], "idle")
}

#[test]
fn a_sweep_as_a_slurm_job_array_gathers_into_the_unsharded_sweep() {
    if !slurm_is_up() {
        skip("Slurm is not running (no `scontrol ping` answering UP with an idle node): run `tools/install-slurm` as root to install and start a single-node Slurm");
        return;
    }
    let dir = std::env::temp_dir().join(format!("lsdc-sweep-slurm-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("directory");
    let program = std::fs::canonicalize("examples/double_pendulum.lsd").expect("example");
    let sweep = [
        "--grid",
        "shoulder.q=0.5:2.5:5",
        "--grid",
        "elbow.q=-1:1:4",
        "--duration",
        "0.5",
    ];
    let whole = dir.join("whole.parquet");
    let args = [
        &["sweep", program.to_str().expect("path")],
        &sweep[..],
        &["-o", whole.to_str().expect("path")],
    ]
    .concat();
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    // The job file of docs/commands.md: one array task per shard.
    let script = format!(
        "#!/bin/sh\n#SBATCH --array=1-4\n#SBATCH --ntasks=1\n#SBATCH --output={dir}/task-%a.log\nexec {lsdc} sweep {program} {sweep} --shard \"$SLURM_ARRAY_TASK_ID/4\" -o {dir}/part-$SLURM_ARRAY_TASK_ID.parquet\n",
        dir = dir.display(),
        lsdc = env!("CARGO_BIN_EXE_lsdc"),
        program = program.display(),
        sweep = sweep.join(" "),
    );
    let job = dir.join("sweep.sbatch");
    std::fs::write(&job, script).expect("job file");
    let submitted = Command::new("sbatch")
        .args([
            "--wait",
            "--chdir",
            dir.to_str().expect("path"),
            job.to_str().expect("path"),
        ])
        .output()
        .expect("sbatch runs");
    let logs: String = (1..=4)
        .map(|k| std::fs::read_to_string(dir.join(format!("task-{k}.log"))).unwrap_or_default())
        .collect();
    assert!(
        submitted.status.success(),
        "sbatch: {}{}\n{logs}",
        String::from_utf8_lossy(&submitted.stdout),
        String::from_utf8_lossy(&submitted.stderr)
    );
    let gathered = dir.join("gathered.parquet");
    let mut args = vec!["sweep".to_string(), "gather".to_string()];
    args.extend((1..=4).map(|k| dir.join(format!("part-{k}.parquet")).display().to_string()));
    args.extend(["-o".to_string(), gathered.display().to_string()]);
    let (code, _, stderr) = lsdc(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 0, "{stderr}\n{logs}");
    let (a, b) = (
        std::fs::read(&gathered).expect("gathered"),
        std::fs::read(&whole).expect("whole"),
    );
    assert!(
        a == b,
        "the job array's gathered file differs from the unsharded sweep"
    );
}

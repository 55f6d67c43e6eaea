//! `plume run --reports FILE`: every firing of the effect's reported events as CSV rows, the
//! same firings (step and id) from the GPU and from the f64 reference, at the same places
//! within the reference comparison's bound; and a located refusal where nothing is reported.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Drops that bounce on a floor (each bounce reported) and die after 0.5 s (reported too).
const EFFECT: &str = r#"Effect(
    name: "drops",
    capacity: 512,
    seed: 9,
    emitters: [Emitter(rate: 400.0, shape: Sphere(center: (0.0, 0.6, 0.0), radius: 0.3),
                       velocity: Radial(speed: (0.5, 1.0)), lifetime: Some((0.5, 0.5)))],
    forces: [Gravity((0.0, -9.81, 0.0))],
    collide: [Plane(point: (0.0, 0.0, 0.0), normal: (0.0, 1.0, 0.0), restitution: 0.5, friction: 0.0)],
    state: Stateful,
    events: [Event(on: Collide, report: 512), Event(on: Death, report: 512)],
)"#;

fn dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plume-run-reports-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn plume(args: &[&str], file: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_plume"))
        .arg("run")
        .args(args)
        .arg(file)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("plume runs")
}

/// A firing's group, event, step and id.
type Key = (String, u32, u64, u32);

/// The rows of a reports CSV: the firing and its six numbers.
fn rows(path: &Path) -> Vec<(Key, [f64; 6])> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("group,event,step,id,x,y,z,vx,vy,vz"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let key = (
                f[0].to_string(),
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
                f[3].parse().unwrap(),
            );
            let nums: Vec<f64> = f[4..].iter().map(|v| v.parse().unwrap()).collect();
            (key, nums.try_into().unwrap())
        })
        .collect()
}

#[test]
fn the_gpu_reports_the_firings_the_reference_fires() {
    let dir = dir();
    let file = dir.join("drops.ron");
    std::fs::write(&file, EFFECT).unwrap();
    let (gpu, cpu) = (dir.join("gpu.csv"), dir.join("cpu.csv"));
    for (out, extra) in [(&gpu, &[][..]), (&cpu, &["--cpu-reference"][..])] {
        let run = plume(
            &[
                &["--steps", "60", "--reports", out.to_str().unwrap()][..],
                extra,
            ]
            .concat(),
            &file,
        );
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(stdout.contains("reported: "), "{stdout}");
    }
    let (gpu, cpu) = (rows(&gpu), rows(&cpu));
    let bounces = cpu.iter().filter(|r| r.0 .1 == 0).count();
    let deaths = cpu.iter().filter(|r| r.0 .1 == 1).count();
    assert!(
        bounces > 50 && deaths > 50,
        "{bounces} bounces, {deaths} deaths"
    );
    assert_eq!(
        gpu.iter().map(|r| &r.0).collect::<Vec<_>>(),
        cpu.iter().map(|r| &r.0).collect::<Vec<_>>()
    );
    // Within a few f32 roundings a step over 60 steps (tests/gpu_vs_reference.rs's bound),
    // relative to 1 + the value.
    for (g, c) in gpu.iter().zip(&cpu) {
        for k in 0..6 {
            let tol = 4.0 * 60.0 / 16_777_216.0 * (1.0 + c.1[k].abs());
            assert!(
                (g.1[k] - c.1[k]).abs() <= tol,
                "{:?}: {:?} vs {:?}",
                g.0,
                g.1,
                c.1
            );
        }
    }
}

#[test]
fn an_effect_without_reported_events_is_refused() {
    let dir = dir();
    let file = dir.join("quiet.ron");
    let quiet = EFFECT.replace(
        "    events: [Event(on: Collide, report: 512), Event(on: Death, report: 512)],\n",
        "",
    );
    assert!(!quiet.contains("events"));
    std::fs::write(&file, quiet).unwrap();
    let out = dir.join("none.csv");
    let run = plume(&["--steps", "5", "--reports", out.to_str().unwrap()], &file);
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        stderr.contains("--reports: no event of this effect is reported"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
}

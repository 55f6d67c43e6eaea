//! Outputs of a run: the summary (bounding box, mean speed, non-finite count) and the particle
//! exports (`.csv`, `.ply`), written atomically (temporary file, then rename).

use std::io::Write;
use std::path::Path;

use glam::DVec3;
use plume_compiler::reference::ParticleRecord;

use crate::error::RuntimeError;

/// Summary statistics of the live particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Particles whose position or velocity has a NaN or Inf component.
    pub nonfinite: u64,
    /// Lower corner of the finite positions (zero when none).
    pub bbox_min: DVec3,
    /// Upper corner of the finite positions (zero when none).
    pub bbox_max: DVec3,
    /// Mean speed of the finite particles (m/s).
    pub mean_speed: f64,
}

/// Computes the [`Summary`] of `records`.
pub fn summarize(records: &[ParticleRecord]) -> Summary {
    let mut s = Summary {
        nonfinite: 0,
        bbox_min: DVec3::splat(f64::INFINITY),
        bbox_max: DVec3::splat(f64::NEG_INFINITY),
        mean_speed: 0.0,
    };
    let mut finite = 0u64;
    let mut speed_sum = 0.0;
    for r in records {
        if !(r.position.is_finite() && r.velocity.is_finite()) {
            s.nonfinite += 1;
            continue;
        }
        finite += 1;
        s.bbox_min = s.bbox_min.min(r.position);
        s.bbox_max = s.bbox_max.max(r.position);
        speed_sum += r.velocity.length();
    }
    if finite == 0 {
        s.bbox_min = DVec3::ZERO;
        s.bbox_max = DVec3::ZERO;
    } else {
        s.mean_speed = speed_sum / finite as f64;
    }
    s
}

/// The CSV export: header `id,x,y,z,vx,vy,vz,age`, one line per particle in id order.
/// Values print with f32's shortest round-trip text for positions and velocities (what the GPU
/// holds) and 9 significant digits for age.
pub fn csv(records: &[ParticleRecord]) -> Vec<u8> {
    let mut out = String::from("id,x,y,z,vx,vy,vz,age\n");
    for r in records {
        let f = |x: f64| format!("{:?}", x as f32);
        out.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            r.id,
            f(r.position.x),
            f(r.position.y),
            f(r.position.z),
            f(r.velocity.x),
            f(r.velocity.y),
            f(r.velocity.z),
            f(r.age)
        ));
    }
    out.into_bytes()
}

/// The PLY export: an ASCII point cloud with position, velocity, id and age per vertex.
pub fn ply(records: &[ParticleRecord]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat ascii 1.0\ncomment written by plume\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float vx\nproperty float vy\nproperty float vz\nproperty uint id\nproperty float age\nend_header\n",
        records.len()
    );
    for r in records {
        out.push_str(&format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {} {:?}\n",
            r.position.x as f32,
            r.position.y as f32,
            r.position.z as f32,
            r.velocity.x as f32,
            r.velocity.y as f32,
            r.velocity.z as f32,
            r.id,
            r.age as f32
        ));
    }
    out.into_bytes()
}

/// Writes `records` to `path` as CSV or PLY (by extension), atomically, never over an input.
pub fn export(
    path: &Path,
    records: &[ParticleRecord],
    inputs: &[&Path],
) -> Result<(), RuntimeError> {
    write_export(path, inputs, || csv(records), || ply(records))
}

/// The CSV export of an effect with groups: header `group,id,x,y,z,vx,vy,vz,age`, each
/// group's particles in id order, groups in file order (ids are per group).
pub fn csv_groups(groups: &[(&str, &[ParticleRecord])]) -> Vec<u8> {
    let mut out = b"group,".to_vec();
    for (g, (name, records)) in groups.iter().enumerate() {
        let text = csv(records);
        let mut lines = text.split(|&b| b == b'\n');
        let header = lines.next().unwrap_or_default();
        if g == 0 {
            out.extend_from_slice(header);
            out.push(b'\n');
        }
        for line in lines.filter(|l| !l.is_empty()) {
            out.extend_from_slice(name.as_bytes());
            out.push(b',');
            out.extend_from_slice(line);
            out.push(b'\n');
        }
    }
    if groups.is_empty() {
        out.extend_from_slice(b"id,x,y,z,vx,vy,vz,age\n");
    }
    out
}

/// The PLY export of an effect with groups: [`ply`]'s vertices with a `group` index, named
/// by `comment group <index> <name>` lines.
pub fn ply_groups(groups: &[(&str, &[ParticleRecord])]) -> Vec<u8> {
    let total: usize = groups.iter().map(|(_, r)| r.len()).sum();
    let mut out = String::from("ply\nformat ascii 1.0\ncomment written by plume\n");
    for (g, (name, _)) in groups.iter().enumerate() {
        out.push_str(&format!("comment group {g} {name}\n"));
    }
    out.push_str(&format!(
        "element vertex {total}\nproperty float x\nproperty float y\nproperty float z\nproperty float vx\nproperty float vy\nproperty float vz\nproperty uint id\nproperty float age\nproperty uint group\nend_header\n"
    ));
    for (g, (_, records)) in groups.iter().enumerate() {
        for r in records.iter() {
            out.push_str(&format!(
                "{:?} {:?} {:?} {:?} {:?} {:?} {} {:?} {g}\n",
                r.position.x as f32,
                r.position.y as f32,
                r.position.z as f32,
                r.velocity.x as f32,
                r.velocity.y as f32,
                r.velocity.z as f32,
                r.id,
                r.age as f32
            ));
        }
    }
    out.into_bytes()
}

/// Writes every group's particles to `path` as CSV or PLY (by extension), atomically, never
/// over an input (see [`csv_groups`], [`ply_groups`]).
pub fn export_groups(
    path: &Path,
    groups: &[(&str, &[ParticleRecord])],
    inputs: &[&Path],
) -> Result<(), RuntimeError> {
    write_export(path, inputs, || csv_groups(groups), || ply_groups(groups))
}

/// Writes the CSV or the PLY bytes (by `path`'s extension) atomically, never over an input.
fn write_export(
    path: &Path,
    inputs: &[&Path],
    csv: impl FnOnce() -> Vec<u8>,
    ply: impl FnOnce() -> Vec<u8>,
) -> Result<(), RuntimeError> {
    let bytes = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv") => csv(),
        Some("ply") => ply(),
        _ => {
            return Err(RuntimeError::Output(format!(
                "{}: unknown export format; use a .csv or .ply file name",
                path.display()
            )))
        }
    };
    write_atomically(path, &bytes, inputs).map_err(RuntimeError::Output)
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so a
/// failed or interrupted run never leaves a truncated file; refuses to overwrite `inputs`.
pub fn write_atomically(path: &Path, bytes: &[u8], inputs: &[&Path]) -> Result<(), String> {
    for input in inputs {
        if let (Ok(a), Ok(b)) = (path.canonicalize(), input.canonicalize()) {
            if a == b {
                return Err(format!(
                    "{}: refusing to overwrite the input file",
                    path.display()
                ));
            }
        }
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: output path has no file name", path.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp-{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: cannot write: {e}", path.display())
    })
}

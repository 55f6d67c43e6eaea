//! The compiler's own speed: RON source to naga-validated WGSL, per example effect.
//! Run with `cargo bench --bench compile`.

use criterion::{criterion_group, criterion_main, Criterion};
use plume::{compile_str, CompileOptions};

fn compile_examples(c: &mut Criterion) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/effects");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("effects/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    let mut group = c.benchmark_group("compile");
    for path in files {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let source = std::fs::read_to_string(&path).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| {
                compile_str(std::hint::black_box(&source), &CompileOptions::default()).unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, compile_examples);
criterion_main!(benches);

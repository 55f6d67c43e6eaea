# Temporary experiment hooks for .bench/plume-exp (never committed): run, build, copy, git checkout crates.
p='crates/plume-runtime/src/sort/radix.rs'
s=open(p).read()
s=s.replace('let sort = module("sort", include_str!("sort.wgsl").to_owned());',
 'let sort = module("sort", include_str!("sort.wgsl").replace("const SCAN_PER: u32 = 8u;", &format!("const SCAN_PER: u32 = {}u;", exp_per())));')
s=s.replace("let blocks = len.div_ceil(if short { TILE } else { SCAN_BLOCK });","let blocks = len.div_ceil(if short { TILE } else { 256 * exp_per() });")
s=s.replace("let scanned_totals = !short && blocks > SCAN_PREFIX_MAX;","let scanned_totals = !short && blocks > std::env::var(\"PLUME_EXP_PREFIX_MAX\").ok().and_then(|v| v.parse().ok()).unwrap_or(SCAN_PREFIX_MAX);")
s+='\nfn exp_per() -> u64 { std::env::var("PLUME_EXP_SCAN_PER").ok().and_then(|v| v.parse().ok()).unwrap_or(8) }\n'
open(p,'w').write(s)
p='crates/plume-compiler/src/features/forces/flock/mod.rs'
s=open(p).read()
old="""        (2 * u64::from(capacity.max(1)))"""
new="""        (std::env::var("PLUME_EXP_BUCKETS").ok().and_then(|v| v.parse().ok()).unwrap_or(2u64) * u64::from(capacity.max(1)))"""
if old in s:
    open(p,'w').write(s.replace(old,new))
p='crates/plume-runtime/src/device/gpu.rs'
s=open(p).read()
old="""    let descriptor = wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),"""
new="""    let mut source: std::borrow::Cow<'a, str> = source.into();
    let key: String = label.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    if let Ok(dir) = std::env::var("PLUME_DUMP_WGSL") {
        let _ = std::fs::write(format!("{dir}/{key}.wgsl"), source.as_ref());
    }
    if let Ok(file) = std::env::var(format!("PLUME_OVERRIDE_{key}")) {
        eprintln!("EXPERIMENT: {label} from {file}");
        source = std::fs::read_to_string(file).expect("override").into();
    }
    let descriptor = wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source),"""
assert old in s
open(p,'w').write(s.replace(old,new))
p='crates/plume-compiler/src/features/forces/flock/grid.rs'
s=open(p).read()
old="emit_run_masked(w, GRID_ONE_LOADS, GRID_ONE_LOADS_PER_ROUND);"
new='emit_run_masked(w, std::env::var("PLUME_EXP_LOADS").ok().and_then(|v| v.parse().ok()).unwrap_or(GRID_ONE_LOADS), std::env::var("PLUME_EXP_PER_ROUND").ok().and_then(|v| v.parse().ok()).unwrap_or(GRID_ONE_LOADS_PER_ROUND));'
assert old in s
open(p,'w').write(s.replace(old,new))
p='crates/plume-compiler/src/features/forces/flock/mod.rs'
s=open(p).read()
old="""        } else {
            GRID_X_SPLIT
        }"""
new="""        } else {
            std::env::var("PLUME_EXP_XSPLIT").ok().and_then(|v| v.parse().ok()).unwrap_or(GRID_X_SPLIT)
        }"""
assert old in s
open(p,'w').write(s.replace(old,new))

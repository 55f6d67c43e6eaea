# Experiment: flock_out records of 64 bytes (4 vec4) instead of 48.
import re
def sub(p, old, new, count=None):
    s=open(p).read()
    assert old in s, (p, old)
    s=s.replace(old,new)
    open(p,'w').write(s)
sub('crates/plume-compiler/src/features/forces/flock/accumulate.rs','flock_out[3u * {slot}','flock_out[4u * {slot}')
sub('crates/plume-compiler/src/features/forces/flock/kernels.rs','flock_out[3u * i','flock_out[4u * i')
sub('crates/plume-compiler/src/stages/passes/layout.rs','bytes: cap * 48,','bytes: cap * 64,')
sub('crates/plume-runtime/src/bench/update.rs','.chunks_exact(48)','.chunks_exact(64)')

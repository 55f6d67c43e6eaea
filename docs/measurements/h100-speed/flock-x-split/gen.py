import sys
S=open('base_search.wgsl').read()
head=S[:S.index('@compute')]
def round_loop(R, ind='            '):
    o=[f"{ind}for (var base = first; base < last; base += {R}u) {{"]
    i2=ind+'    '
    for j in range(R): o.append(f"{i2}let x{j} = boids[2u * (base + {j}u)];")
    o.append(f"{i2}var hits = 0u;")
    for j in range(R):
        o.append(f"{i2}let d{j} = me.xyz - x{j}.xyz;")
        o.append(f"{i2}hits |= select(0u, {1<<j}u, x{j}.w == key && dot(d{j}, d{j}) < FLOCK_R2);")
    o.append(f"{i2}hits &= (2u << (min(last - base, {R}u) - 1u)) - 1u;")
    o.append(f"{i2}hits &= select(0xffffffffu, ~(1u << (k - base)), k - base < {R}u);")
    o.append(f"""{i2}while (hits != 0u) {{
{i2}    let m = base + firstTrailingBit(hits);
{i2}    hits &= hits - 1u;
{i2}    let xm = boids[2u * m];
{i2}    let vm = boids[2u * m + 1u];
{i2}    let d = me.xyz - xm.xyz;
{i2}    let f = flock_pair(d, dot(d, d), heading);
{i2}    push += f.xyz;
{i2}    sum_x += f.w * xm.xyz;
{i2}    sum_v += f.w * vm.xyz;
{i2}    sum_w += f.w;
{i2}    count += 1.0;
{i2}}}""")
    o.append(f"{ind}}}")
    return "\n".join(o)

# The search kernel's start: its boid, its sums, its cell.
PROLOGUE = """    let k = gid.x + gid.y * groups.x * WORKGROUP;
    if (k >= cell_start[GRID_BUCKETS]) {
        return;
    }
    let me = boids[2u * k];
    let me_v = boids[2u * k + 1u];
    let heading = flock_heading(me_v.xyz);
    var push = vec3<f32>(0.0);
    var sum_x = vec3<f32>(0.0);
    var sum_v = vec3<f32>(0.0);
    var sum_w = 0.0;
    var count = 0.0;
    let home = cell_of(me.xyz);"""

def rows_end(R, wrapped):
    """A row's first run's rounds, its wrapped run, the end of the row loop and the results."""
    middle = ("\n        }\n        let wrapped = " + wrapped + ";\n        if (wrapped > 0u) {\n"
              "            let first = cell_start[0];\n            let last = cell_start[wrapped];\n")
    return "\n" + round_loop(R) + middle + round_loop(R) + """
        }
    }
    flock_out[3u * grid_vals[k]] = vec4<f32>(push, sum_w);
    flock_out[3u * grid_vals[k] + 1u] = vec4<f32>(sum_x, count);
    flock_out[3u * grid_vals[k] + 2u] = vec4<f32>(sum_v, 0.0);
}
"""

def kernel(R, wg=256, shared=False, xs=1):
    h=head.replace("const WORKGROUP: u32 = 256u;", f"const WORKGROUP: u32 = {wg}u;")
    if xs>1:
        h=h.replace("const INV_CELL: f32 = 1.25;", f"const INV_CELL: vec3<f32> = vec3<f32>({1.25*xs}, 1.25, 1.25);")
    nb=2*xs+1
    off=f"home + vec3<i32>(-{xs}, n % 3 - 1, n / 3 - 1)"
    o=[]
    if shared:
        o.append(f"var<workgroup> run_words: array<u32, {27*wg}u>;")
    o.append("@compute @workgroup_size(WORKGROUP)")
    o.append("fn flock_grid(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {")
    o.append(PROLOGUE)
    if not shared:
        o.append("    var runs: array<vec3<u32>, 9>;")
    o.append(f"""    for (var n = 0; n < 9; n++) {{
        let b0 = bucket_of({off});
        let wrapped = max(b0 + {nb}u, GRID_BUCKETS) - GRID_BUCKETS;""")
    if shared:
        o.append(f"""        run_words[u32(3 * n) * WORKGROUP + lid] = cell_start[b0];
        run_words[u32(3 * n + 1) * WORKGROUP + lid] = cell_start[min(b0 + {nb}u, GRID_BUCKETS)];
        run_words[u32(3 * n + 2) * WORKGROUP + lid] = wrapped;""")
        F="run_words[u32(3 * n) * WORKGROUP + lid]"; L="run_words[u32(3 * n + 1) * WORKGROUP + lid]"; W="run_words[u32(3 * n + 2) * WORKGROUP + lid]"
    else:
        o.append(f"        runs[n] = vec3<u32>(cell_start[b0], cell_start[min(b0 + {nb}u, GRID_BUCKETS)], wrapped);")
        F="runs[n].x"; L="runs[n].y"; W="runs[n].z"
    o.append("    }")
    o.append(f"""    for (var n = 0; n < 9; n++) {{
        let key = row_key({off});
        {{
            let first = {F};
            let last = {L};""")
    return h + "\n".join(o) + rows_end(R, W)

def kernel_cull(R, xs=3):
    """x split in xs sub-cells; each row clipped to the sub-cells within reach (exact set)."""
    h=head.replace("const INV_CELL: f32 = 1.25;", f"const INV_CELL: vec3<f32> = vec3<f32>({1.25*xs}, 1.25, 1.25);")
    o=[]
    o.append("@compute @workgroup_size(WORKGROUP)")
    o.append("fn flock_grid(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {")
    o.append(PROLOGUE)
    o.append(f"""    // Margin for rounding: cell membership and these bounds, relative to the coordinates.
    let slack = 1e-3 * 0.8 + 2.4e-7 * (max(max(abs(me.x), abs(me.y)), abs(me.z)) + 0.8);
    let clamped = any(abs(home) >= vec3<i32>(999990));
    var runs: array<vec3<u32>, 9>;
    for (var n = 0; n < 9; n++) {{
        let c = home + vec3<i32>(0, n % 3 - 1, n / 3 - 1);
        let lo_yz = vec2<f32>(c.yz) / INV_CELL.yz;
        let gap = max(max(lo_yz - me.yz, me.yz - (lo_yz + 1.0 / INV_CELL.yz)), vec2<f32>(0.0));
        let reach2 = FLOCK_R2 - dot(gap, gap);
        var lo = home.x - {xs};
        var hi = home.x + {xs};
        var live_row = true;
        if (!clamped) {{
            let reach = sqrt(max(reach2, 0.0)) + slack;
            live_row = reach2 > -2.0 * slack * 0.8;
            lo = max(lo, i32(floor((me.x - reach) * INV_CELL.x)));
            hi = min(hi, i32(floor((me.x + reach) * INV_CELL.x)));
        }}
        let b0 = bucket_of(vec3<i32>(lo, c.y, c.z));
        let nb = u32(hi - lo + 1);
        let wrapped = max(b0 + nb, GRID_BUCKETS) - GRID_BUCKETS;
        let first = cell_start[b0];
        let last = cell_start[min(b0 + nb, GRID_BUCKETS)];
        runs[n] = select(vec3<u32>(0u), vec3<u32>(first, last, wrapped), live_row);
    }}
    for (var n = 0; n < 9; n++) {{
        let key = row_key(home + vec3<i32>(0, n % 3 - 1, n / 3 - 1));
        {{
            let first = runs[n].x;
            let last = runs[n].y;""")
    return h + "\n".join(o) + rows_end(R, "runs[n].z")

// The lobe micro-benchmark: each invocation evaluates the lobe REPS times on its own
// cosine (nudged each time, so nothing can be hoisted) and writes the sum. FORM 0 is
// pow as GPUs compute it, exp2(n log2 c): two special-function instructions; FORM 1
// is K_v (or any power fit): one FMA and V multiplies (glint-lobe's Form::Power).

override FORM: u32 = 0u;
override V: u32 = 4u;

struct Bench {
    // n, a, repetitions, count.
    p: vec4<f32>,
}

@group(0) @binding(0) var<uniform> B: Bench;
@group(0) @binding(1) var<storage, read> cosines: array<f32>;
@group(0) @binding(2) var<storage, read_write> sums: array<f32>;

@compute @workgroup_size(64, 1, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * 65535u * 64u + gid.x;
    if i >= u32(B.p.w) {
        return;
    }
    var c = cosines[i];
    var s = 0.0;
    let reps = u32(B.p.z);
    for (var r = 0u; r < reps; r++) {
        var y: f32;
        if FORM == 0u {
            y = exp2(B.p.x * log2(max(c, 1e-30)));
        } else {
            var b = max(1.0 - B.p.y * (1.0 - c), 0.0);
            for (var k = 0u; k < V; k++) {
                b = b * b;
            }
            y = b;
        }
        s += y;
        c = c * 0.9999 + 0.00005;
    }
    sums[i] = s;
}

//! The GPU sorts (llvmpipe in CI) against a CPU stable sort, at sizes that are and are not
//! powers of two (7,327 broke a peer's sort), with many equal keys.

mod common;

use common::*;
use plume::compiler::rng::pcg;
use plume::runtime::bench::{GpuSorter, Ranking, SortAlgorithm};
use plume::runtime::oracle;

/// Deterministic keys; `distinct` bounds how many different keys there are (ties test stability).
fn keys(n: usize, distinct: u32) -> Vec<u32> {
    (0..n as u32).map(|i| pcg(i ^ 0xabcd) % distinct).collect()
}

fn check(sorter: &GpuSorter, algorithm: SortAlgorithm, n: usize, distinct: u32) {
    let k = keys(n, distinct);
    let v: Vec<u32> = (0..n as u32).collect();
    let (gk, gv) = sorter.sort_pairs(algorithm, &k, &v).unwrap();
    // CPU reference: stable sort by key, values are the original positions.
    let mut expected: Vec<(u32, u32)> = k.iter().copied().zip(v.iter().copied()).collect();
    expected.sort_by_key(|p| p.0);
    let got: Vec<(u32, u32)> = gk.into_iter().zip(gv).collect();
    assert_eq!(got.len(), n);
    if let Some(i) = (0..n).find(|&i| got[i] != expected[i]) {
        panic!("{algorithm:?}, n = {n}, {distinct} keys: first difference at {i}: got {:?}, expected {:?}", got[i], expected[i]);
    }
}

/// The rankings `gpu` can run: the portable one always, subgroup ballots where the adapter has
/// subgroups of 32, and those in one dispatch a pass (OneSweep) on NVIDIA (the H100 runs all
/// three; llvmpipe the portable ranking alone).
fn sorters(gpu: &plume::runtime::Gpu) -> Vec<GpuSorter> {
    let out: Vec<GpuSorter> = Ranking::runnable_on(gpu)
        .into_iter()
        .map(|ranking| GpuSorter::with_ranking(gpu, ranking).unwrap())
        .collect();
    eprintln!(
        "rankings tested on {}: {:?}",
        gpu.info.name,
        out.iter().map(GpuSorter::ranking).collect::<Vec<_>>()
    );
    out
}

#[test]
fn radix_sort_matches_a_stable_cpu_sort_at_every_size() {
    let gpu = gpu();
    for sorter in sorters(&gpu) {
        radix_sort_matches_at_every_size(&sorter);
    }
}

fn radix_sort_matches_at_every_size(sorter: &GpuSorter) {
    // Around one tile (256 keys) and one partition (2,048 keys), and awkward sizes past them.
    for n in [
        0, 1, 2, 3, 255, 256, 257, 1000, 2047, 2048, 2049, 7327, 65537,
    ] {
        check(sorter, SortAlgorithm::Radix, n, u32::MAX);
        check(sorter, SortAlgorithm::Radix, n, 7);
    }
    // Keys that differ only in the top byte, and the extremes.
    let k: Vec<u32> = (0..5000u32)
        .map(|i| ((i % 3) << 24) | (u32::from(i % 2 == 0) * 0xffff_ff00))
        .collect();
    let v: Vec<u32> = (0..5000).collect();
    let (gk, gv) = sorter.sort_pairs(SortAlgorithm::Radix, &k, &v).unwrap();
    let mut e: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
    e.sort_by_key(|p| p.0);
    assert_eq!(gk.into_iter().zip(gv).collect::<Vec<_>>(), e);
}

#[test]
fn scans_match_a_cpu_prefix_sum_and_the_scan_from_a_source_clears_it() {
    let gpu = gpu();
    let sorter = GpuSorter::new(&gpu);
    // Short scans (up to 65,536 words, blocks of 256): none, one word, one block and the
    // first word of a second, the flock grid's 2^15 + 1 buckets, the longest short scan. Long
    // ones (blocks of 2,048, eight words a thread): the shortest, a block ending inside a
    // thread's eight words, the most blocks whose workgroups add up the totals before their own
    // (2,048) and the first size past it (its totals scanned by a dispatch of their own), and
    // the flock grid's 2M + 1 buckets at 1M boids.
    for n in [
        0, 1, 255, 256, 257, 32_769, 65_536, 65_537, 600_001, 2_097_153, 4_194_304, 4_194_305,
    ] {
        let words: Vec<u32> = (0..n as u32).map(|i| pcg(i) % 5).collect();
        let expected: Vec<u32> = words
            .iter()
            .scan(0u32, |sum, &w| {
                let before = *sum;
                *sum += w;
                Some(before)
            })
            .collect();
        let (in_place, untouched) = sorter.scan_words(&words, false).unwrap();
        assert_eq!(in_place, expected, "in place, n = {n}");
        assert_eq!(
            untouched, words,
            "the in-place scan read no source, n = {n}"
        );
        let (scanned, source) = sorter.scan_words(&words, true).unwrap();
        assert_eq!(scanned, expected, "from a source, n = {n}");
        assert!(
            source.iter().all(|&w| w == 0),
            "source not cleared, n = {n}"
        );
    }
}

#[test]
fn radix_sort_of_a_million_keys() {
    let gpu = gpu();
    for sorter in sorters(&gpu) {
        check(&sorter, SortAlgorithm::Radix, 1 << 20, u32::MAX);
        // Depth keys share their high digits: one digit value fills whole partitions.
        check(&sorter, SortAlgorithm::Radix, 1 << 20, 300);
    }
}

#[test]
fn asking_for_a_ranking_the_adapter_lacks_is_an_error() {
    let gpu = gpu();
    let subgroup = GpuSorter::with_ranking(&gpu, Ranking::Subgroup);
    assert_eq!(subgroup.is_ok(), gpu.has_subgroups_of(32));
    if let Err(e) = subgroup {
        assert!(e.to_string().contains("subgroups"), "{e}");
    }
    let onesweep = GpuSorter::with_ranking(&gpu, Ranking::OneSweep);
    assert_eq!(
        onesweep.is_ok(),
        Ranking::runnable_on(&gpu).contains(&Ranking::OneSweep)
    );
    if let Err(e) = onesweep {
        assert!(e.to_string().contains("NVIDIA"), "{e}");
    }
}

#[test]
fn bitonic_baseline_matches_too() {
    let gpu = gpu();
    let sorter = GpuSorter::new(&gpu);
    for n in [1, 2, 1000, 7327, 65537] {
        check(&sorter, SortAlgorithm::Bitonic, n, u32::MAX);
        check(&sorter, SortAlgorithm::Bitonic, n, 5);
    }
}

#[test]
fn draw_order_is_back_to_front_with_ties_by_id_and_covers_every_live_particle() {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/effects/fountain.ron"))
        .unwrap();
    let e = compile(&src);
    assert!(e.ir.sort);
    let gpu = gpu();
    let mut sim = plume::runtime::Effect::new(&gpu, e.clone()).unwrap();
    sim.run(150, |_| {}).unwrap();
    let by_id = sim.records().unwrap();
    let drawn = sim.records_in_draw_order().unwrap();
    assert_eq!(drawn.len(), by_id.len());
    let mut ids: Vec<u32> = drawn.iter().map(|r| r.id).collect();
    ids.sort_unstable();
    assert_eq!(
        ids,
        by_id.iter().map(|r| r.id).collect::<Vec<_>>(),
        "draw order lost or repeated a particle"
    );
    // Depths (recomputed in f64 from the exported f32 positions) never increase by more than
    // one step of the quantised keys.
    assert_back_to_front(&e, &drawn);
    // The keys the sort ordered: 16 bits, live ones at most 65,533, in order.
    let order = oracle::draw_order(&sim, SortAlgorithm::Radix).unwrap();
    assert!(order.windows(2).all(|w| w[0].1 <= w[1].1));
    assert!(
        order.iter().all(|&(_, key)| key <= 65533),
        "a live key past 65,533"
    );
    // The radix sort maps the depth keys to 16 bits as its first pass reads them; the bitonic
    // sort's path maps them in place first, with a kernel of its own. The same keys, and (ties
    // in slot order both ways) the same order.
    assert_eq!(
        order,
        oracle::draw_order(&sim, SortAlgorithm::Bitonic).unwrap(),
        "the radix sort's quantised keys differ from the in-place map's"
    );
}

#[test]
fn particles_at_one_depth_share_key_zero_and_keep_slot_order() {
    // Every live depth equal: the range is empty, and quantising must neither divide by zero
    // nor produce anything but key 0 (the sort then keeps slot order, which is id order here).
    let e = compile(
        r#"Effect(
            name: "one depth",
            capacity: 64,
            emitters: [Emitter(burst: 40, shape: Point((1.0, 2.0, 3.0)), velocity: Constant((0.0, 0.0, 0.0)))],
            forces: [],
            sort: true,
        )"#,
    );
    let gpu = gpu();
    let mut sim = plume::runtime::Effect::new(&gpu, e.clone()).unwrap();
    sim.run(2, |_| {}).unwrap();
    let order = oracle::draw_order(&sim, SortAlgorithm::Radix).unwrap();
    assert_eq!(order.len(), 40);
    assert!(order.iter().all(|&(_, key)| key == 0), "{order:?}");
    let slots: Vec<u32> = order.iter().map(|&(slot, _)| slot).collect();
    assert_eq!(slots, (0..40).collect::<Vec<u32>>());
}

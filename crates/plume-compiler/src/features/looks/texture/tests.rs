use super::*;

fn atlas(columns: u32, rows: u32, play: Play) -> TextureIr {
    TextureIr {
        file: "t.png".into(),
        width: 4 * columns,
        height: 4 * rows,
        rgba: vec![0; (16 * columns * rows * 4) as usize].into(),
        columns,
        rows,
        play,
        random_start: false,
        sample: Sample::Modulate,
        second: None,
        missing: None,
    }
}

#[test]
fn over_life_frames_split_the_life_evenly() {
    let t = atlas(2, 2, Play::OverLife);
    // 8 steps of life, 4 frames: 2 steps each; the last frame holds at the end.
    let frames: Vec<u32> = (0..=9).map(|lived| t.frame(0, 0, lived, 8, 0.1)).collect();
    assert_eq!(frames, [0, 0, 1, 1, 2, 2, 3, 3, 3, 3]);
    assert_eq!(
        t.frame(0, 0, 5, 0, 0.1),
        0,
        "a particle that never dies shows frame 0"
    );
}

#[test]
fn rate_frames_loop_and_start_on_their_step() {
    // 0.1 s steps at 5 frames per second: a frame every 2 steps; 0.1 * 5 is not exact in
    // binary, and the epsilon keeps step 2 on frame 1.
    let t = atlas(3, 1, Play::Rate(5.0));
    let frames: Vec<u32> = (0..8).map(|lived| t.frame(0, 0, lived, 0, 0.1)).collect();
    assert_eq!(frames, [0, 0, 1, 1, 2, 2, 0, 0]);
}

#[test]
fn a_random_start_shifts_each_loop_by_its_own_frame() {
    let t = TextureIr {
        random_start: true,
        sample: Sample::Modulate,
        ..atlas(4, 1, Play::Rate(10.0))
    };
    let mut starts = [0; 4];
    for id in 0..400 {
        let start = t.frame(id, 7, 0, 0, 0.1);
        starts[start as usize] += 1;
        // Still one frame per step at 10 frames per second, in order, wrapping.
        for lived in 1..6 {
            assert_eq!(t.frame(id, 7, lived, 0, 0.1), (start + lived as u32) % 4);
        }
    }
    assert!(
        starts.iter().all(|&n| n > 60),
        "starts spread over the frames: {starts:?}"
    );
}

#[test]
fn frame_rectangles_read_left_to_right_top_to_bottom() {
    let t = atlas(3, 2, Play::OverLife);
    assert_eq!(t.frame_texels(0), [0, 0, 4, 4]);
    assert_eq!(t.frame_texels(2), [8, 0, 4, 4]);
    assert_eq!(t.frame_texels(4), [4, 4, 4, 4]);
}

#[test]
fn a_single_image_never_animates() {
    let t = atlas(1, 1, Play::Rate(30.0));
    assert!(!t.animated() && !t.needs_age_of_immortals());
    assert_eq!(t.frame(0, 0, 1000, 0, 0.1), 0);
}

use super::*;
use embedded_graphics::mock_display::MockDisplay;
use embedded_graphics::pixelcolor::Rgb565;

/// A 64x64 display that panics on any pixel drawn outside it, so every test
/// here also checks the clipping.
fn display() -> MockDisplay<Rgb565> {
    let mut d = MockDisplay::new();
    d.set_allow_overdraw(true);
    d
}

fn at(d: &MockDisplay<Rgb565>, x: i32, y: i32) -> Option<Rgb565> {
    d.get_pixel(Point::new(x, y))
}

/// Pixels of `colour` in the inclusive rectangle `(x0, y0)..=(x1, y1)`.
fn count(d: &MockDisplay<Rgb565>, (x0, y0): (i32, i32), (x1, y1): (i32, i32), c: Rgb565) -> usize {
    (y0..=y1)
        .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
        .filter(|&(x, y)| at(d, x, y) == Some(c))
        .count()
}

fn drawn(d: &MockDisplay<Rgb565>) -> usize {
    (0..64)
        .flat_map(|y| (0..64).map(move |x| (x, y)))
        .filter(|&(x, y)| at(d, x, y).is_some())
        .count()
}

fn draw(labels: &[ObjectLabel<'_>]) -> MockDisplay<Rgb565> {
    let mut d = display();
    draw_objects(&mut d, labels, &LabelStyle::default()).unwrap();
    d
}

#[test]
fn a_known_box_is_outlined_on_its_edge_pixels() {
    let d = draw(&[ObjectLabel::new(10, 20, 30, 15, "cup", true)]);
    let g = Some(Rgb565::GREEN);
    // Corners and the middle of each edge.
    for (x, y) in [
        (10, 20),
        (39, 20),
        (10, 34),
        (39, 34),
        (25, 34),
        (10, 27),
        (39, 27),
    ] {
        assert_eq!(at(&d, x, y), g, "({x}, {y})");
    }
    // The whole outline: 2 * 30 + 2 * 13 pixels, solid.
    assert_eq!(
        count(&d, (10, 20), (39, 34), Rgb565::GREEN),
        2 * 30 + 2 * 13
    );
    // Just outside and just inside stay untouched.
    for (x, y) in [(9, 27), (40, 27), (25, 35), (11, 21), (38, 33), (25, 27)] {
        assert_eq!(at(&d, x, y), None, "({x}, {y})");
    }
}

#[test]
fn the_tab_sits_above_the_box_with_text_inside() {
    let d = draw(&[ObjectLabel::new(10, 20, 30, 15, "cup", true)]);
    // 6x10 font: "cup" is 18 px wide; the tab adds a pixel each side.
    let (w, h) = (20, 12);
    let (x0, y0) = (10, 20 - h);
    let text = count(&d, (x0, y0), (x0 + w - 1, y0 + h - 1), Rgb565::BLACK);
    let fill = count(&d, (x0, y0), (x0 + w - 1, y0 + h - 1), Rgb565::GREEN);
    assert!(text > 15, "only {text} text pixels in the tab");
    assert_eq!(text + fill, (w * h) as usize, "tab not filled");
    // The tab's border pixels are fill, not text.
    assert_eq!(at(&d, x0, y0), Some(Rgb565::GREEN));
    // Nothing right of the tab or above it.
    assert_eq!(at(&d, x0 + w, y0 + 5), None);
    assert_eq!(at(&d, x0 + 5, y0 - 1), None);
}

#[test]
fn the_score_widens_the_tab_and_is_capped_at_100() {
    let d = draw(&[ObjectLabel::new(2, 30, 10, 10, "x", true).with_score(250)]);
    // "x 100%" is 6 characters: 36 px + 2.
    assert_eq!(at(&d, 2 + 37, 25), Some(Rgb565::GREEN));
    assert_eq!(at(&d, 2 + 38, 25), None);
    let text = count(&d, (2 + 7, 18), (2 + 37, 29), Rgb565::BLACK);
    assert!(text > 30, "score text missing: {text}");
}

#[test]
fn without_room_above_the_tab_goes_inside_the_box() {
    let d = draw(&[ObjectLabel::new(5, 3, 40, 30, "ball", true)]);
    // Tab from row 3 (the box's top) to row 14.
    let text = count(&d, (5, 3), (5 + 25, 14), Rgb565::BLACK);
    assert!(text > 15, "{text}");
    assert_eq!(at(&d, 5, 15), Some(Rgb565::GREEN)); // left edge below the tab
    assert_eq!(at(&d, 6, 15), None);
    assert_eq!(count(&d, (0, 0), (63, 2), Rgb565::GREEN), 0);
}

#[test]
fn unknown_objects_get_a_dashed_outline_in_their_own_colour() {
    let d = draw(&[ObjectLabel::new(10, 20, 30, 15, "?", false)]);
    // 4 of every 6 pixels along the bottom edge, the corner at x = 39
    // left out (the right edge draws it): 29 px -> 20.
    let bottom = count(&d, (10, 34), (38, 34), Rgb565::MAGENTA);
    assert_eq!(bottom, 20);
    assert_eq!(count(&d, (10, 34), (39, 34), Rgb565::GREEN), 0);
    assert_eq!(at(&d, 10, 34), Some(Rgb565::MAGENTA));
    assert_eq!(at(&d, 14, 34), None);
    let right = count(&d, (39, 20), (39, 34), Rgb565::MAGENTA);
    assert!((9..15).contains(&right), "{right}");
}

#[test]
fn boxes_past_the_frame_edges_are_clipped_not_wrapped() {
    // MockDisplay panics on any pixel drawn outside 64x64.
    let d = draw(&[ObjectLabel::new(-10, -10, 30, 30, "top left", true)]);
    // Only the right (x = 19) and bottom (y = 19) edges are in the frame.
    assert!(count(&d, (19, 0), (19, 19), Rgb565::GREEN) > 5);
    assert_eq!(at(&d, 5, 19), Some(Rgb565::GREEN));
    // The tab is pulled into the frame at the top-left corner.
    assert!(count(&d, (0, 0), (40, 11), Rgb565::BLACK) > 20);

    // A box at the right edge: the tab shifts left to stay whole.
    let d = draw(&[ObjectLabel::new(50, 30, 30, 10, "bottle 99", true)]);
    // 9 characters: 56 px wide, so it starts at 64 - 56 = 8.
    assert_eq!(at(&d, 8, 18), Some(Rgb565::GREEN));
    assert_eq!(at(&d, 7, 18), None);
    assert_eq!(at(&d, 63, 18), Some(Rgb565::GREEN));
    assert_eq!(at(&d, 50, 39), Some(Rgb565::GREEN)); // left edge, bottom
    assert_eq!(at(&d, 63, 35), None); // the right edge is at x = 79
}

#[test]
fn extreme_boxes_do_not_panic() {
    let huge = [
        ObjectLabel::new(i32::MIN, i32::MIN, u32::MAX, u32::MAX, "all", true),
        ObjectLabel::new(i32::MAX, i32::MAX, u32::MAX, u32::MAX, "far", false),
        ObjectLabel::new(i32::MAX - 3, 10, 10, 10, "edge", true),
        ObjectLabel::new(60, 60, 100, 100, "a long label past the edge", false),
    ];
    let d = draw(&huge);
    // The first covers the whole frame (edges outside): only its tab shows.
    assert!(count(&d, (0, 0), (63, 11), Rgb565::BLACK) > 0);
    // The last shows its corner.
    assert_eq!(at(&d, 60, 60), Some(Rgb565::MAGENTA));
}

#[test]
fn boxes_outside_the_frame_or_of_zero_size_draw_nothing() {
    let labels = [
        ObjectLabel::new(64, 10, 10, 10, "right", true),
        ObjectLabel::new(10, -30, 10, 10, "above", true),
        ObjectLabel::new(10, 10, 0, 10, "thin", true),
        ObjectLabel::new(10, 10, 10, 0, "flat", false),
        ObjectLabel::new(0, 0, 0, 0, "", true),
    ];
    assert_eq!(drawn(&draw(&labels)), 0);
    // A one-pixel box is its own outline.
    let d = draw(&[ObjectLabel::new(30, 40, 1, 1, "", true)]);
    assert_eq!(at(&d, 30, 40), Some(Rgb565::GREEN));
}

#[test]
fn the_first_object_tab_is_drawn_on_top() {
    let a = ObjectLabel::new(10, 30, 20, 20, "AAAA", true);
    let b = ObjectLabel::new(12, 30, 20, 20, "BBBB", false);
    let d = draw(&[a, b]);
    // The tabs overlap at rows 18..29, x = 12 to 35; the first's (green)
    // fill shows there, not the second's magenta.
    assert!(count(&d, (12, 18), (33, 29), Rgb565::GREEN) > 0);
    assert_eq!(at(&d, 12, 18), Some(Rgb565::GREEN));
    assert_eq!(at(&d, 36, 18), Some(Rgb565::MAGENTA));
}

#[test]
fn a_caption_fills_its_strip_and_picks_a_font_that_fits() {
    let strip = Rectangle::new(Point::new(0, 20), Size::new(64, CAPTION_HEIGHT));
    let style = CaptionStyle::default();
    for text in [
        "(a) left",
        "(g) region C",
        "(g) object region conspicuity",
        "",
    ] {
        let mut d = display();
        caption(&mut d.cropped(&strip), text, &style).unwrap();
        let (white, black) = (
            count(&d, (0, 20), (63, 31), Rgb565::WHITE),
            count(&d, (0, 20), (63, 31), Rgb565::BLACK),
        );
        assert_eq!(white + black, 64 * 12, "{text}: strip not filled");
        assert_eq!(drawn(&d), 64 * 12, "{text}: drew outside the strip");
        assert_eq!(white > 0, !text.is_empty(), "{text}");
    }
    // 12 characters: 72 px in 6x10 do not fit 64, 60 in 5x8 do; the text
    // then ends by x = 1 + 60.
    let mut d = display();
    caption(&mut d.cropped(&strip), "(g) region C", &style).unwrap();
    assert!(count(&d, (1, 20), (60, 31), Rgb565::WHITE) > 20);
    assert_eq!(count(&d, (61, 20), (63, 31), Rgb565::WHITE), 0);
}

#[test]
fn captions_in_tiny_targets_do_not_panic() {
    let style = CaptionStyle::default();
    for size in [
        Size::new(0, 0),
        Size::new(1, 1),
        Size::new(64, 3),
        Size::new(3, 64),
    ] {
        let mut d = display();
        caption(
            &mut d.cropped(&Rectangle::new(Point::zero(), size)),
            "caption",
            &style,
        )
        .unwrap();
        assert!(drawn(&d) <= (size.width * size.height) as usize);
    }
}

#[test]
fn text_width_matches_embedded_graphics() {
    assert_eq!(text_width(&FONT_6X10, 0), 0);
    assert_eq!(text_width(&FONT_6X10, 3), 18);
    assert_eq!(text_width(&FONT_4X6, 5), 20);
    assert_eq!(text_width(&FONT_6X10, usize::MAX), u32::MAX);
}

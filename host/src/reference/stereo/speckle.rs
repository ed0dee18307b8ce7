//! Speckle filter (an opt-in OFF test of `protogist stereo`, docs/STEREO.md
//! "Third round: the speckle filter"): a pixel goes OFF when it lies in a
//! small island of the map.
//!
//! Two ON pixels are joined when they are 4-neighbours and their
//! disparities differ by at most `max_diff` px; an island (a connected set
//! of joined pixels) of at most `max_size` pixels is set OFF. This is
//! OpenCV's `filterSpeckles` on a map with OFF pixels, which never join
//! anything. It targets the matcher's isolated confident mistakes: a wrong
//! disparity rarely agrees with a large patch of its neighbours, a right
//! one on a surface usually does.

/// The pixels of `map` (`w x h`, row-major, `None`: OFF) that lie in an
/// island of at most `max_size` pixels: `true` where the filter turns a
/// pixel OFF. `max_size` 0 removes nothing. A `map` whose length is not
/// `w · h` is treated as all OFF (nothing removed).
pub fn speckles(
    map: &[Option<f32>],
    w: usize,
    h: usize,
    max_size: usize,
    max_diff: f32,
) -> Vec<bool> {
    let n = map.len();
    let mut removed = vec![false; n];
    if max_size == 0 || n != w * h {
        return removed;
    }
    let mut visited = vec![false; n];
    let mut island = Vec::new();
    let mut stack = Vec::new();
    for seed in 0..n {
        if visited[seed] || map[seed].is_none() {
            continue;
        }
        visited[seed] = true;
        island.clear();
        stack.push(seed);
        while let Some(p) = stack.pop() {
            island.push(p);
            let Some(d) = map[p] else { continue };
            let (x, y) = (p % w, p / w);
            let neighbours = [
                (x > 0).then(|| p - 1),
                (x + 1 < w).then(|| p + 1),
                (y > 0).then(|| p - w),
                (y + 1 < h).then(|| p + w),
            ];
            for q in neighbours.into_iter().flatten() {
                if !visited[q] && map[q].is_some_and(|e| (e - d).abs() <= max_diff) {
                    visited[q] = true;
                    stack.push(q);
                }
            }
        }
        if island.len() <= max_size {
            for &p in &island {
                removed[p] = true;
            }
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::speckles;

    /// A 6x4 map: a 2x2 plateau at 9 inside a field at 2, one OFF pixel.
    fn scene() -> Vec<Option<f32>> {
        let mut m = vec![Some(2.0); 24];
        for p in [7, 8, 13, 14] {
            m[p] = Some(9.0);
        }
        m[23] = None;
        m
    }

    #[test]
    fn a_small_island_goes_off_and_the_field_around_it_stays() {
        let r = speckles(&scene(), 6, 4, 4, 1.0);
        let off: Vec<usize> = (0..24).filter(|&p| r[p]).collect();
        assert_eq!(off, vec![7, 8, 13, 14]);
    }

    #[test]
    fn an_island_larger_than_the_size_stays() {
        assert!(speckles(&scene(), 6, 4, 3, 1.0).iter().all(|&r| !r));
    }

    #[test]
    fn a_wide_range_joins_the_island_to_the_field() {
        // |9 − 2| = 7 ≤ 7: one island of 23 ON pixels.
        assert!(speckles(&scene(), 6, 4, 4, 7.0).iter().all(|&r| !r));
        assert!(speckles(&scene(), 6, 4, 23, 7.0)[..23].iter().all(|&r| r));
    }

    #[test]
    fn joins_follow_small_steps_and_not_the_diagonal() {
        // A ramp of 0.5 px steps is one island; a diagonal pair is two.
        let ramp: Vec<Option<f32>> = (0..8).map(|x| Some(x as f32 * 0.5)).collect();
        assert!(speckles(&ramp, 8, 1, 7, 1.0).iter().all(|&r| !r));
        let diag = vec![Some(1.0), None, None, Some(1.0)];
        assert_eq!(
            speckles(&diag, 2, 2, 1, 1.0),
            vec![true, false, false, true]
        );
    }

    #[test]
    fn off_pixels_are_never_removed_and_a_bad_size_removes_nothing() {
        let r = speckles(&scene(), 6, 4, 30, 1.0);
        assert!(!r[23]);
        assert!(speckles(&scene(), 5, 4, 30, 1.0).iter().all(|&r| !r));
        assert!(speckles(&scene(), 6, 4, 0, 1.0).iter().all(|&r| !r));
    }
}

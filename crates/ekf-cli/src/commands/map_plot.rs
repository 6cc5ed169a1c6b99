//! `ekf map plot MAP.json --svg OUT.svg [--trajectory T.tum]…`: a line map drawn to scale,
//! with trajectories over it.

use super::figures::walls_of;
use crate::plot::{plot_figure, Panel, PlotError, PlotOptions, TrajectorySeries};
use crate::trajectory::Trajectory;
use lrf_lines::LineMap;
use std::io::Write;

/// Draws `map`'s walls (grey) and the `trajectories` (named, coloured in order) in one
/// chart with equal scales, titled `title`, and writes the SVG to `writer`.
pub fn plot_map<W: Write>(
    writer: W,
    map: &LineMap,
    trajectories: &[(String, Trajectory)],
    title: &str,
) -> Result<(), PlotError> {
    let walls = walls_of(&map.segments);
    let estimates: Vec<TrajectorySeries<'_>> = trajectories
        .iter()
        .map(|(name, trajectory)| TrajectorySeries { name, trajectory })
        .collect();
    let panels = [Panel::Trajectories {
        title: "",
        reference: None,
        estimates: &estimates,
        walls: &walls,
        markers: &[],
    }];
    let options = PlotOptions {
        title: title.to_string(),
        ..PlotOptions::default()
    };
    plot_figure(writer, &panels, 1, &options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ekf_core::Pose2;
    use lrf_lines::MapSegment;
    use nalgebra::Point2;

    #[test]
    fn walls_and_each_trajectory_are_drawn_with_a_legend() {
        let wall = |a: (f64, f64), b: (f64, f64)| {
            MapSegment::from_points(Point2::new(a.0, a.1), Point2::new(b.0, b.1)).unwrap()
        };
        let map = LineMap::new(vec![
            wall((0.0, 0.0), (4.0, 0.0)),
            wall((4.0, 0.0), (4.0, 3.0)),
        ]);
        let mut t = Trajectory::default();
        for k in 0..5 {
            t.push(k * 1_000_000_000, Pose2::new(0.5 * k as f64, 1.0, 0.0));
        }
        let mut svg = Vec::new();
        plot_map(
            &mut svg,
            &map,
            &[("est-trajectory".into(), t)],
            "office-map",
        )
        .unwrap();
        let svg = String::from_utf8(svg).unwrap();
        let text = |s: &str| svg.contains(&format!(">\n{s}\n</text>"));
        assert!(text("office-map"), "title");
        assert!(text("walls") && text("est-trajectory"), "legend");
        // Two walls in wall grey and one trajectory in the first colour, each with its
        // legend glyph.
        assert_eq!(svg.matches(r##"stroke="#969696""##).count(), 3, "{svg}");
        assert_eq!(svg.matches(r##"stroke="#1F77B4""##).count(), 2, "{svg}");
        let mut empty = Vec::new();
        assert!(matches!(
            plot_map(&mut empty, &LineMap::default(), &[], ""),
            Err(PlotError::NoData)
        ));
    }
}

//! Workpiece and tool path: what the tool cuts where.
//!
//! A scenario is a sequence of linear and circular moves (each with its programmed feed and
//! spindle speed), a cutter and a milling mode, and three functions of the distance s travelled
//! along the path:
//!
//! * the axial depth of cut a(s) and the radial width of cut a_e(s), piecewise linear
//!   ([`Profile`]: a step is two points at the same s, a taper two points apart);
//! * the work material, piecewise constant ([`MaterialRegion`]; no region = air).
//!
//! Air cuts are where the depth or width is 0 or there is no material. The scenario itself does
//! not move anything: the CNC ([`super::cnc`]) decides how fast s advances, the simulator reads
//! the geometry at the actual s each sample. Everything here is plain data for the UI to draw:
//! [`Scenario::polyline`], [`Scenario::depth_profile`], [`Scenario::width_profile`],
//! [`Scenario::material_regions`].
//!
//! Lookups past the ends clamp to the first or last point; NaN positions give NaN values.

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, TAU};

use super::cnc::PlanBlock;
use super::materials::Material;
use super::mechanics::{Cutter, MillingMode};
use super::{finite, non_negative, positive, PlantError};
use crate::math;

/// The shape of a move.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MoveKind {
    /// G01: a straight line.
    Line,
    /// G02 (clockwise) or G03: an arc about `center_mm`; an end equal to the start is a full
    /// circle.
    Arc {
        /// Centre of the arc.
        center_mm: [f64; 2],
        /// G02 when true, G03 when false.
        clockwise: bool,
    },
}

/// One programmed move, from the previous end point to `end_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Move {
    /// End point (x, y).
    pub end_mm: [f64; 2],
    /// Line or arc.
    pub kind: MoveKind,
    /// Programmed feed F of the block.
    pub feed_mm_min: f64,
    /// Spindle speed S of the block.
    pub spindle_rpm: f64,
}

impl Move {
    /// A G01 line to `end_mm`.
    pub fn line(end_mm: [f64; 2], feed_mm_min: f64, spindle_rpm: f64) -> Self {
        Self {
            end_mm,
            kind: MoveKind::Line,
            feed_mm_min,
            spindle_rpm,
        }
    }

    /// A G02/G03 arc to `end_mm` about `center_mm`.
    pub fn arc(
        end_mm: [f64; 2],
        center_mm: [f64; 2],
        clockwise: bool,
        feed_mm_min: f64,
        spindle_rpm: f64,
    ) -> Self {
        Self {
            end_mm,
            kind: MoveKind::Arc {
                center_mm,
                clockwise,
            },
            feed_mm_min,
            spindle_rpm,
        }
    }
}

/// One point of a profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfilePoint {
    /// Distance along the path.
    pub position_mm: f64,
    /// Value there.
    pub value: f64,
}

/// A piecewise-linear function of path distance, constant beyond its ends.
///
/// ```
/// use cutlab::plant::scenario::Profile;
/// // Depth 1 mm, a step to 2 mm at 10 mm, then a taper to 4 mm at 20 mm.
/// let p = Profile::new(&[(0.0, 1.0), (10.0, 1.0), (10.0, 2.0), (20.0, 4.0)], "depth").unwrap();
/// assert_eq!(p.value_at(5.0), 1.0);
/// assert_eq!(p.value_at(10.0), 2.0); // a step takes its upper value at the step
/// assert!((p.value_at(15.0) - 3.0).abs() < 1e-12);
/// assert_eq!(p.value_at(99.0), 4.0);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    points: Vec<ProfilePoint>,
}

impl Profile {
    /// A profile through `(position_mm, value)` points with non-decreasing positions and finite
    /// values ≥ 0; `field` names it in errors.
    pub fn new(points: &[(f64, f64)], field: &str) -> Result<Self, PlantError> {
        if points.is_empty() {
            return Err(PlantError::new(field, "needs at least one point"));
        }
        let mut out = Vec::with_capacity(points.len());
        let mut last = f64::NEG_INFINITY;
        for (i, &(s, v)) in points.iter().enumerate() {
            finite(&format!("{field}[{i}].position_mm"), s)?;
            non_negative(&format!("{field}[{i}].value"), v)?;
            if s < last {
                return Err(PlantError::new(
                    format!("{field}[{i}].position_mm"),
                    format!("positions must not decrease: {s} after {last}"),
                ));
            }
            last = s;
            out.push(ProfilePoint {
                position_mm: s,
                value: v,
            });
        }
        Ok(Self { points: out })
    }

    /// A constant profile.
    pub fn constant(value: f64, field: &str) -> Result<Self, PlantError> {
        Self::new(&[(0.0, value)], field)
    }

    /// The points, for drawing.
    pub fn points(&self) -> &[ProfilePoint] {
        &self.points
    }

    /// The largest value.
    pub fn max_value(&self) -> f64 {
        self.points.iter().map(|p| p.value).fold(0.0, f64::max)
    }

    /// The value at `position_mm`.
    pub fn value_at(&self, position_mm: f64) -> f64 {
        let mut hint = 0;
        self.value_from_hint(position_mm, &mut hint)
    }

    /// [`Profile::value_at`], starting the search from the point index `hint` the call before
    /// left there (O(1) for a monotone walk along the path, as the simulator makes one).
    #[inline(always)]
    pub(crate) fn value_from_hint(&self, position_mm: f64, hint: &mut usize) -> f64 {
        if position_mm.is_nan() {
            return f64::NAN;
        }
        let p = &self.points;
        // The first point strictly beyond s: at a step (two equal positions) s takes the later
        // point's value.
        let h = (*hint).min(p.len());
        let i = if (h == 0 || p[h - 1].position_mm <= position_mm)
            && p.get(h).is_none_or(|q| q.position_mm > position_mm)
        {
            h
        } else {
            p.partition_point(|q| q.position_mm <= position_mm)
        };
        *hint = i;
        if i == 0 {
            return p[0].value;
        }
        if i == p.len() {
            return p[p.len() - 1].value;
        }
        let (a, b) = (p[i - 1], p[i]);
        let t = (position_mm - a.position_mm) / (b.position_mm - a.position_mm);
        a.value + t * (b.value - a.value)
    }
}

/// A stretch of the path cut in one material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MaterialRegion {
    /// Where it starts along the path.
    pub from_mm: f64,
    /// Where it ends.
    pub to_mm: f64,
    /// The material.
    pub material: Material,
}

/// Everything needed to build a [`Scenario`]: plain data, serialisable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioSpec {
    /// Short name.
    pub name: String,
    /// Start point of the path.
    pub start_mm: [f64; 2],
    /// The moves.
    pub moves: Vec<Move>,
    /// The cutter.
    pub cutter: Cutter,
    /// Up, down or slot.
    pub mode: MillingMode,
    /// Axial depth a(s) as (position, depth) points.
    pub depth_mm: Vec<(f64, f64)>,
    /// Radial width a_e(s) as (position, width) points.
    pub width_mm: Vec<(f64, f64)>,
    /// Material regions along the path, in order, not overlapping.
    pub materials: Vec<MaterialRegion>,
    /// Dwell after the spindle reaches speed before the first move.
    pub spindle_start_dwell_s: f64,
}

/// Where a path segment lies, precomputed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PathSegment {
    /// Path distance at the segment's start.
    pub start_mm: f64,
    /// Its length.
    pub length_mm: f64,
    /// Start point.
    pub from_mm: [f64; 2],
    /// End point.
    pub to_mm: [f64; 2],
    /// Arc centre, radius, start angle and signed sweep (None for a line).
    pub arc: Option<ArcGeometry>,
    /// Direction of a line (counter-clockwise from +x); for an arc, that of its start.
    pub direction_rad: f64,
    /// Programmed feed.
    pub feed_mm_min: f64,
    /// Spindle speed.
    pub spindle_rpm: f64,
}

/// An arc's geometry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ArcGeometry {
    /// Centre.
    pub center_mm: [f64; 2],
    /// Radius.
    pub radius_mm: f64,
    /// Angle of the start point about the centre (counter-clockwise from +x).
    pub start_angle_rad: f64,
    /// Swept angle, negative for clockwise.
    pub sweep_rad: f64,
}

/// A point on the path.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PathPoint {
    /// Position.
    pub position_mm: [f64; 2],
    /// Direction of motion, counter-clockwise from +x.
    pub direction_rad: f64,
    /// cos of the direction.
    pub direction_cos: f64,
    /// sin of the direction.
    pub direction_sin: f64,
    /// Index of the segment.
    pub segment: usize,
}

/// A validated scenario.
///
/// ```
/// use cutlab::plant::materials::Material;
/// use cutlab::plant::mechanics::{Cutter, MillingMode};
/// use cutlab::plant::scenario::{MaterialRegion, Move, Scenario, ScenarioSpec};
/// let s = Scenario::new(ScenarioSpec {
///     name: "slot".into(),
///     start_mm: [0.0, 0.0],
///     moves: vec![Move::line([50.0, 0.0], 200.0, 1000.0)],
///     cutter: Cutter::new(20.0, 2, 30.0).unwrap(),
///     mode: MillingMode::Slot,
///     depth_mm: vec![(0.0, 2.0)],
///     width_mm: vec![(0.0, 20.0)],
///     materials: vec![MaterialRegion { from_mm: 10.0, to_mm: 50.0, material: Material::Sm45c }],
///     spindle_start_dwell_s: 0.0,
/// }).unwrap();
/// assert_eq!(s.total_length_mm(), 50.0);
/// assert_eq!(s.material_at(5.0), None);
/// assert_eq!(s.material_at(20.0), Some(Material::Sm45c));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scenario {
    spec: ScenarioSpec,
    segments: Vec<PathSegment>,
    depth: Profile,
    width: Profile,
    regions: Vec<MaterialRegion>,
}

impl Scenario {
    /// Validates `spec` and precomputes its geometry.
    pub fn new(spec: ScenarioSpec) -> Result<Self, PlantError> {
        spec.cutter.validate().map_err(|e| e.within("cutter"))?;
        for (i, v) in spec.start_mm.iter().enumerate() {
            finite(&format!("start_mm[{i}]"), *v)?;
        }
        if spec.moves.is_empty() {
            return Err(PlantError::new("moves", "the program has no moves"));
        }
        let mut segments = Vec::with_capacity(spec.moves.len());
        let mut from = spec.start_mm;
        let mut s = 0.0;
        for (i, m) in spec.moves.iter().enumerate() {
            let field = |f: &str| format!("moves[{i}].{f}");
            finite(&field("end_mm[0]"), m.end_mm[0])?;
            finite(&field("end_mm[1]"), m.end_mm[1])?;
            positive(&field("feed_mm_min"), m.feed_mm_min)?;
            non_negative(&field("spindle_rpm"), m.spindle_rpm)?;
            let (length_mm, arc) = match m.kind {
                MoveKind::Line => {
                    let l = math::hypot(m.end_mm[0] - from[0], m.end_mm[1] - from[1]);
                    if l < 1e-9 {
                        return Err(PlantError::new(field("end_mm"), "the line has no length"));
                    }
                    (l, None)
                }
                MoveKind::Arc {
                    center_mm,
                    clockwise,
                } => {
                    finite(&field("center_mm[0]"), center_mm[0])?;
                    finite(&field("center_mm[1]"), center_mm[1])?;
                    let r0 = math::hypot(from[0] - center_mm[0], from[1] - center_mm[1]);
                    let r1 = math::hypot(m.end_mm[0] - center_mm[0], m.end_mm[1] - center_mm[1]);
                    if r0 < 1e-6 {
                        return Err(PlantError::new(
                            field("center_mm"),
                            "the centre lies on the start point",
                        ));
                    }
                    if (r0 - r1).abs() > 1e-3 {
                        return Err(PlantError::new(
                            field("end_mm"),
                            format!(
                                "start and end lie at different radii ({r0:.4} and {r1:.4} mm)"
                            ),
                        ));
                    }
                    let a0 = math::atan2(from[1] - center_mm[1], from[0] - center_mm[0]);
                    let a1 = math::atan2(m.end_mm[1] - center_mm[1], m.end_mm[0] - center_mm[0]);
                    let mut sweep = (a1 - a0).rem_euclid(TAU);
                    if sweep < 1e-9 {
                        sweep = TAU; // end == start: a full circle
                    }
                    if clockwise {
                        sweep -= TAU;
                        if sweep > -1e-9 {
                            sweep = -TAU;
                        }
                    }
                    (
                        r0 * sweep.abs(),
                        Some(ArcGeometry {
                            center_mm,
                            radius_mm: r0,
                            start_angle_rad: a0,
                            sweep_rad: sweep,
                        }),
                    )
                }
            };
            let direction_rad = match arc {
                None => math::atan2(m.end_mm[1] - from[1], m.end_mm[0] - from[0]),
                Some(a) => a.start_angle_rad + a.sweep_rad.signum() * FRAC_PI_2,
            };
            segments.push(PathSegment {
                start_mm: s,
                length_mm,
                from_mm: from,
                to_mm: m.end_mm,
                arc,
                direction_rad,
                feed_mm_min: m.feed_mm_min,
                spindle_rpm: m.spindle_rpm,
            });
            s += length_mm;
            from = m.end_mm;
        }
        let depth = Profile::new(&spec.depth_mm, "depth_mm")?;
        let deepest_mm = spec.depth_mm.iter().map(|p| p.1).fold(0.0, f64::max);
        if deepest_mm > spec.cutter.max_axial_depth_mm() {
            return Err(PlantError::new(
                "depth_mm",
                format!(
                    "{deepest_mm} mm is deeper than this cutter's helix can be modelled ({:.0} mm)",
                    spec.cutter.max_axial_depth_mm()
                ),
            ));
        }
        let width = Profile::new(&spec.width_mm, "width_mm")?;
        let mut regions = Vec::new();
        let mut last_end = f64::NEG_INFINITY;
        for (i, r) in spec.materials.iter().enumerate() {
            let field = |f: &str| format!("materials[{i}].{f}");
            finite(&field("from_mm"), r.from_mm)?;
            finite(&field("to_mm"), r.to_mm)?;
            if r.to_mm <= r.from_mm {
                return Err(PlantError::new(field("to_mm"), "must lie after from_mm"));
            }
            if r.from_mm < last_end {
                return Err(PlantError::new(
                    field("from_mm"),
                    "regions must be in order and must not overlap",
                ));
            }
            last_end = r.to_mm;
            let mut start = r.from_mm;
            for &(fraction, material) in r.material.layers() {
                let end = start + fraction * (r.to_mm - r.from_mm);
                regions.push(MaterialRegion {
                    from_mm: start,
                    to_mm: end,
                    material,
                });
                start = end;
            }
        }
        non_negative("spindle_start_dwell_s", spec.spindle_start_dwell_s)?;
        Ok(Self {
            spec,
            segments,
            depth,
            width,
            regions,
        })
    }

    /// The specification it was built from.
    pub fn spec(&self) -> &ScenarioSpec {
        &self.spec
    }

    /// The name.
    pub fn name(&self) -> &str {
        &self.spec.name
    }

    /// The cutter.
    pub fn cutter(&self) -> &Cutter {
        &self.spec.cutter
    }

    /// The milling mode.
    pub fn mode(&self) -> MillingMode {
        self.spec.mode
    }

    /// The path segments.
    pub fn segments(&self) -> &[PathSegment] {
        &self.segments
    }

    /// Total path length.
    pub fn total_length_mm(&self) -> f64 {
        self.segments
            .last()
            .map_or(0.0, |s| s.start_mm + s.length_mm)
    }

    /// The depth profile a(s).
    pub fn depth_profile(&self) -> &Profile {
        &self.depth
    }

    /// The width profile a_e(s).
    pub fn width_profile(&self) -> &Profile {
        &self.width
    }

    /// Material regions with composites split into their layers.
    pub fn material_regions(&self) -> &[MaterialRegion] {
        &self.regions
    }

    /// The material at `position_mm`, `None` in air.
    pub fn material_at(&self, position_mm: f64) -> Option<Material> {
        let i = self.regions.partition_point(|r| r.to_mm <= position_mm);
        self.regions
            .get(i)
            .filter(|r| r.from_mm <= position_mm)
            .map(|r| r.material)
    }

    /// Index of the region at `position_mm`, `None` in air (for the simulator's cache); the
    /// search starts from `hint`, the index the call before left there.
    #[inline(always)]
    pub(crate) fn region_index_from_hint(
        &self,
        position_mm: f64,
        hint: &mut usize,
    ) -> Option<usize> {
        let r = &self.regions;
        // The first region that ends beyond s.
        let h = (*hint).min(r.len());
        let i = if (h == 0 || r[h - 1].to_mm <= position_mm)
            && r.get(h).is_none_or(|q| q.to_mm > position_mm)
        {
            h
        } else {
            r.partition_point(|q| q.to_mm <= position_mm)
        };
        *hint = i;
        self.regions
            .get(i)
            .filter(|r| r.from_mm <= position_mm)
            .map(|_| i)
    }

    /// The segment containing `position_mm` (clamped to the path).
    pub fn segment_at(&self, position_mm: f64) -> usize {
        let i = self
            .segments
            .partition_point(|s| s.start_mm + s.length_mm <= position_mm);
        i.min(self.segments.len() - 1)
    }

    /// The point at distance `position_mm` along the path (clamped to its ends).
    ///
    /// ```
    /// use cutlab::plant::presets::Preset;
    /// let s = Preset::KimCircularTaper.scenario().unwrap();
    /// let p = s.point_at(0.0);
    /// assert_eq!(p.position_mm, s.spec().start_mm);
    /// ```
    pub fn point_at(&self, position_mm: f64) -> PathPoint {
        self.point_in_segment(position_mm, self.segment_at(position_mm))
    }

    /// The point at `position_mm` searching forward from segment `hint` (O(1) for a monotone
    /// walk along the path).
    #[inline(always)]
    pub(crate) fn point_from_hint(&self, position_mm: f64, hint: usize) -> PathPoint {
        let mut i = hint.min(self.segments.len() - 1);
        if self.segments[i].start_mm > position_mm {
            i = self.segment_at(position_mm);
        }
        while i + 1 < self.segments.len()
            && position_mm >= self.segments[i].start_mm + self.segments[i].length_mm
        {
            i += 1;
        }
        self.point_in_segment(position_mm, i)
    }

    #[inline(always)]
    fn point_in_segment(&self, position_mm: f64, i: usize) -> PathPoint {
        let seg = &self.segments[i];
        let d = math::clamp(position_mm - seg.start_mm, 0.0, seg.length_mm);
        match seg.arc {
            None => {
                let t = d / seg.length_mm;
                let dx = seg.to_mm[0] - seg.from_mm[0];
                let dy = seg.to_mm[1] - seg.from_mm[1];
                PathPoint {
                    position_mm: [seg.from_mm[0] + t * dx, seg.from_mm[1] + t * dy],
                    direction_rad: seg.direction_rad,
                    direction_cos: dx / seg.length_mm,
                    direction_sin: dy / seg.length_mm,
                    segment: i,
                }
            }
            Some(arc) => {
                let sign = arc.sweep_rad.signum();
                let angle = arc.start_angle_rad + sign * d / arc.radius_mm;
                let (s, c) = (math::sin(angle), math::cos(angle));
                // The tangent is the radius turned by ±90°.
                PathPoint {
                    position_mm: [
                        arc.center_mm[0] + arc.radius_mm * c,
                        arc.center_mm[1] + arc.radius_mm * s,
                    ],
                    direction_rad: angle + sign * FRAC_PI_2,
                    direction_cos: -sign * s,
                    direction_sin: sign * c,
                    segment: i,
                }
            }
        }
    }

    /// The path as a polyline for drawing, chords no longer than `max_chord_mm` on arcs.
    ///
    /// ```
    /// use cutlab::plant::presets::Preset;
    /// let s = Preset::KimStepDoc.scenario().unwrap();
    /// let line = s.polyline(1.0);
    /// assert_eq!(line.first(), Some(&s.spec().start_mm));
    /// ```
    pub fn polyline(&self, max_chord_mm: f64) -> Vec<[f64; 2]> {
        let chord = if max_chord_mm.is_finite() && max_chord_mm > 0.0 {
            max_chord_mm
        } else {
            1.0
        };
        let mut out = vec![self.spec.start_mm];
        for (i, seg) in self.segments.iter().enumerate() {
            match seg.arc {
                None => out.push(seg.to_mm),
                Some(_) => {
                    let n = (seg.length_mm / chord).ceil().clamp(1.0, 10_000.0) as usize;
                    for k in 1..=n {
                        let s = seg.start_mm + seg.length_mm * k as f64 / n as f64;
                        out.push(self.point_in_segment(s, i).position_mm);
                    }
                }
            }
        }
        out
    }

    /// Lower-left and upper-right corners of the path's bounding box.
    ///
    /// ```
    /// use cutlab::plant::presets::Preset;
    /// let (lo, hi) = Preset::KimCircularTaper.scenario().unwrap().bounds_mm();
    /// assert!((lo[0] + 45.0).abs() < 1e-9 && (hi[0] - 40.0).abs() < 1e-9);
    /// assert!((hi[1] - 20.0).abs() < 1e-3 && (lo[1] + 20.0).abs() < 1e-3);
    /// ```
    pub fn bounds_mm(&self) -> ([f64; 2], [f64; 2]) {
        let points = self.polyline(0.5);
        points.iter().fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            },
        )
    }

    /// The blocks the feed planner walks.
    pub fn plan_blocks(&self) -> Vec<PlanBlock> {
        self.segments
            .iter()
            .enumerate()
            .map(|(i, seg)| {
                let start = self.point_in_segment(seg.start_mm, i).direction_rad;
                let end = self
                    .point_in_segment(seg.start_mm + seg.length_mm, i)
                    .direction_rad;
                PlanBlock {
                    length_mm: seg.length_mm,
                    feed_mm_min: seg.feed_mm_min,
                    radius_mm: seg.arc.map_or(f64::INFINITY, |a| a.radius_mm),
                    start_direction_rad: start,
                    end_direction_rad: end,
                }
            })
            .collect()
    }

    /// Estimated run time at 100 % override: path length over programmed feed, plus the dwell
    /// (acceleration, corners and spindle start not counted).
    ///
    /// ```
    /// use cutlab::plant::presets::Preset;
    /// let s = Preset::KimStepDoc.scenario().unwrap(); // 180 mm at 200 mm/min
    /// assert!((s.nominal_duration_s() - 54.0).abs() < 1e-9);
    /// ```
    pub fn nominal_duration_s(&self) -> f64 {
        self.segments
            .iter()
            .map(|s| s.length_mm / s.feed_mm_min * 60.0)
            .sum::<f64>()
            + self.spec.spindle_start_dwell_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(moves: Vec<Move>) -> ScenarioSpec {
        ScenarioSpec {
            name: "t".into(),
            start_mm: [0.0, 0.0],
            moves,
            cutter: Cutter::new(10.0, 2, 30.0).unwrap(),
            mode: MillingMode::Slot,
            depth_mm: vec![(0.0, 1.0)],
            width_mm: vec![(0.0, 10.0)],
            materials: vec![],
            spindle_start_dwell_s: 0.0,
        }
    }

    #[test]
    fn a_semicircle_has_length_pi_r_and_turns_the_right_way() {
        // From (0,0) about (10,0) counter-clockwise: the tool goes down first.
        let s = Scenario::new(spec(vec![Move::arc(
            [20.0, 0.0],
            [10.0, 0.0],
            false,
            100.0,
            1000.0,
        )]))
        .unwrap();
        assert!((s.total_length_mm() - std::f64::consts::PI * 10.0).abs() < 1e-9);
        let mid = s.point_at(s.total_length_mm() / 2.0);
        assert!((mid.position_mm[0] - 10.0).abs() < 1e-9);
        assert!((mid.position_mm[1] + 10.0).abs() < 1e-9);
        assert!((mid.direction_rad.cos() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_full_circle_returns_to_its_start() {
        let s = Scenario::new(spec(vec![Move::arc(
            [0.0, 0.0],
            [5.0, 0.0],
            true,
            100.0,
            1000.0,
        )]))
        .unwrap();
        assert!((s.total_length_mm() - TAU * 5.0).abs() < 1e-9);
        let end = s.point_at(s.total_length_mm());
        assert!(end.position_mm[0].abs() < 1e-9 && end.position_mm[1].abs() < 1e-9);
    }

    #[test]
    fn inconsistent_arcs_and_overlapping_regions_name_their_field() {
        let e = Scenario::new(spec(vec![Move::arc(
            [30.0, 0.0],
            [10.0, 0.0],
            false,
            100.0,
            1.0,
        )]))
        .unwrap_err();
        assert_eq!(e.field, "moves[0].end_mm");
        let mut sp = spec(vec![Move::line([10.0, 0.0], 100.0, 1000.0)]);
        sp.materials = vec![
            MaterialRegion {
                from_mm: 0.0,
                to_mm: 6.0,
                material: Material::Gc30,
            },
            MaterialRegion {
                from_mm: 5.0,
                to_mm: 9.0,
                material: Material::Gc30,
            },
        ];
        assert_eq!(Scenario::new(sp).unwrap_err().field, "materials[1].from_mm");
    }

    #[test]
    fn composite_regions_split_into_steel_then_aluminium() {
        let mut sp = spec(vec![Move::line([100.0, 0.0], 100.0, 1000.0)]);
        sp.materials = vec![MaterialRegion {
            from_mm: 20.0,
            to_mm: 80.0,
            material: Material::Composite,
        }];
        let s = Scenario::new(sp).unwrap();
        assert_eq!(s.material_at(49.0), Some(Material::Sm45c));
        assert_eq!(s.material_at(51.0), Some(Material::Aluminium));
        assert_eq!(s.material_at(81.0), None);
    }

    #[test]
    fn profiles_refuse_decreasing_positions() {
        let e = Profile::new(&[(1.0, 1.0), (0.5, 1.0)], "depth_mm").unwrap_err();
        assert_eq!(e.field, "depth_mm[1].position_mm");
        assert!(Profile::constant(2.0, "w")
            .unwrap()
            .value_at(f64::NAN)
            .is_nan());
    }

    #[test]
    fn hinted_lookup_equals_the_plain_one() {
        let s = Scenario::new(spec(vec![
            Move::line([10.0, 0.0], 100.0, 1000.0),
            Move::arc([20.0, 0.0], [15.0, 0.0], true, 100.0, 1000.0),
            Move::line([20.0, 10.0], 100.0, 1000.0),
        ]))
        .unwrap();
        let mut hint = 0;
        for k in 0..400 {
            let pos = 0.1 * f64::from(k);
            let a = s.point_from_hint(pos, hint);
            hint = a.segment;
            assert_eq!(a, s.point_at(pos));
        }
    }
}

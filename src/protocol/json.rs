//! Frames as JSON objects, for `cutlab protocol decode` and `encode` and for people debugging a
//! bridge with a serial sniffer.
//!
//! A frame is an object with its `"type"` ([`FrameType::name`]) and its fields by the names of
//! the structs in [`super::frame`], in wire units (counts, hundredths of a percent, µs).
//! Text fields (`device_id`, `program`) are strings; enumerations (`override_mode`, `result`,
//! `kind`) are names, or numbers for codes this version does not know; `f32` fields are numbers
//! (NaN and ±∞ are `null`, which encodes as NaN). Encoding takes the same objects, strictly: a
//! field the frame type does not have is an error listing the fields it has ([`field_names`]),
//! and so is a field left out, except a `flags` or `faults` byte, which then has no bit set
//! ([`DEFAULT_ZERO_FIELDS`]); so are a field given twice ([`parse_line`]), a number beyond an
//! `f32` field's range (it would become ±∞ on the wire) and a NUL in a text field (it would end
//! the text there). An error quotes at most 40 characters of a bad value.
//!
//! ```
//! use cutlab::protocol::frame::{Frame, Arm};
//! use cutlab::protocol::json::{frame_from_json, frame_to_json};
//! let v = frame_to_json(&Frame::Arm(Arm { seq: 7 }));
//! assert_eq!(v.to_string(), r#"{"seq":7,"type":"arm"}"#);
//! assert_eq!(frame_from_json(&v), Ok(Frame::Arm(Arm { seq: 7 })));
//! ```

use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::{json, Map, Value};

use crate::input::excerpt;
use crate::truth_fields::TRUTH_VALUES;

use super::frame::{
    padded, text_field, Ack, AckResult, Arm, Capabilities, Disarm, Fault, FaultKind, Frame,
    FrameType, Heartbeat, Hello, OverrideModeCode, Reset, Sample, SetOverride, SimTruth,
    DEVICE_ID_LEN, PROGRAM_LEN,
};

fn mode_name(m: OverrideModeCode) -> Value {
    match m {
        OverrideModeCode::Dial16 => json!("dial16"),
        OverrideModeCode::WholePercent => json!("whole-percent"),
        OverrideModeCode::Continuous => json!("continuous"),
        OverrideModeCode::Other(c) => json!(c),
    }
}

fn result_name(r: AckResult) -> Value {
    match r {
        AckResult::Applied => json!("applied"),
        AckResult::Limited => json!("limited"),
        AckResult::NotArmed => json!("not-armed"),
        AckResult::Refused => json!("refused"),
        AckResult::Stale => json!("stale"),
        AckResult::CauseActive => json!("cause-active"),
        AckResult::Other(c) => json!(c),
    }
}

fn kind_name(k: FaultKind) -> Value {
    match k {
        FaultKind::Other(c) => json!(c),
        k => json!(k.name()),
    }
}

fn text(bytes: &[u8]) -> Value {
    match text_field(bytes) {
        Some(t) => json!(t),
        None => json!(bytes),
    }
}

/// The JSON object of `frame`.
pub fn frame_to_json(frame: &Frame) -> Value {
    let mut v = match frame {
        Frame::Hello(h) => {
            json!({"version_major": h.version_major, "version_minor": h.version_minor})
        }
        Frame::Capabilities(c) => json!({
            "version_major": c.version_major,
            "version_minor": c.version_minor,
            "device_id": text(&c.device_id),
            "program": text(&c.program),
            "channel_mask": c.channel_mask,
            "spindle_current_a_per_count": c.spindle_current_a_per_count,
            "feed_current_a_per_count": c.feed_current_a_per_count,
            "fv_v_per_count": c.fv_v_per_count,
            "sample_rate_hz": c.sample_rate_hz,
            "override_mode": mode_name(c.override_mode),
            "min_override_cpct": c.min_override_cpct,
            "max_override_cpct": c.max_override_cpct,
            "dial_cpct": c.dial_cpct,
            "watchdog_timeout_ms": c.watchdog_timeout_ms,
            "fallback_override_cpct": c.fallback_override_cpct,
            "over_current_a": c.over_current_a,
            "features": c.features,
            "measured": c.measured,
            "fallback_limit_ms": c.fallback_limit_ms,
            "line_baud": c.line_baud,
        }),
        Frame::Sample(s) => json!({
            "seq": s.seq,
            "time_us": s.time_us,
            "flags": s.flags,
            "spindle_current_counts": s.spindle_current_counts,
            "feed_current_counts": s.feed_current_counts,
            "fv_counts": s.fv_counts,
            "spindle_speed_rpm": s.spindle_speed_rpm,
            "spindle_command_rpm": s.spindle_command_rpm,
            "programmed_feed_mm_min": s.programmed_feed_mm_min,
            "feed_mm_min": s.feed_mm_min,
            "applied_override_cpct": s.applied_override_cpct,
            "dial_code": s.dial_code,
            "faults": s.faults,
        }),
        Frame::SimTruth(t) => {
            let mut m = Map::new();
            m.insert("seq".into(), json!(t.seq));
            for (name, value) in SimTruth::NAMES.iter().zip(t.values()) {
                m.insert((*name).into(), json!(value));
            }
            Value::Object(m)
        }
        Frame::SetOverride(c) => {
            json!({
                "seq": c.seq,
                "override_cpct": c.override_cpct,
                "flags": c.flags,
                "sample_time_us": c.sample_time_us,
            })
        }
        Frame::Arm(a) => json!({"seq": a.seq}),
        Frame::Disarm(d) => json!({"seq": d.seq}),
        Frame::Reset(r) => json!({"seq": r.seq}),
        Frame::Ack(a) => json!({
            "seq": a.seq,
            "command": FrameType::from_code(a.command).map_or(json!(a.command), |t| json!(t.name())),
            "result": result_name(a.result),
            "applied_override_cpct": a.applied_override_cpct,
            "flags": a.flags,
        }),
        Frame::Fault(f) => json!({
            "seq": f.seq,
            "time_us": f.time_us,
            "kind": kind_name(f.kind),
            "active": f.active,
            "channel": f.channel,
            "applied_override_cpct": f.applied_override_cpct,
        }),
        Frame::Heartbeat(h) => json!({
            "seq": h.seq,
            "time_us": h.time_us,
            "flags": h.flags,
            "faults": h.faults,
            "last_sample_seq": h.last_sample_seq,
        }),
    };
    if let Value::Object(m) = &mut v {
        m.insert("type".into(), json!(frame.frame_type().name()));
    }
    v
}

/// The fields of a frame type's JSON object, in wire order (`"type"` aside).
///
/// ```
/// use cutlab::protocol::frame::FrameType;
/// use cutlab::protocol::json::field_names;
/// assert_eq!(
///     field_names(FrameType::SetOverride),
///     ["seq", "override_cpct", "flags", "sample_time_us"]
/// );
/// ```
pub fn field_names(frame_type: FrameType) -> &'static [&'static str] {
    match frame_type {
        FrameType::Hello => &["version_major", "version_minor"],
        FrameType::Capabilities => &[
            "version_major",
            "version_minor",
            "device_id",
            "program",
            "channel_mask",
            "spindle_current_a_per_count",
            "feed_current_a_per_count",
            "fv_v_per_count",
            "sample_rate_hz",
            "override_mode",
            "min_override_cpct",
            "max_override_cpct",
            "dial_cpct",
            "watchdog_timeout_ms",
            "fallback_override_cpct",
            "over_current_a",
            "features",
            "measured",
            "fallback_limit_ms",
            "line_baud",
        ],
        FrameType::Sample => &[
            "seq",
            "time_us",
            "flags",
            "spindle_current_counts",
            "feed_current_counts",
            "fv_counts",
            "spindle_speed_rpm",
            "spindle_command_rpm",
            "programmed_feed_mm_min",
            "feed_mm_min",
            "applied_override_cpct",
            "dial_code",
            "faults",
        ],
        FrameType::SimTruth => &SIM_TRUTH_FIELDS,
        FrameType::SetOverride => &["seq", "override_cpct", "flags", "sample_time_us"],
        FrameType::Arm | FrameType::Disarm | FrameType::Reset => &["seq"],
        FrameType::Ack => &["seq", "command", "result", "applied_override_cpct", "flags"],
        FrameType::Fault => &[
            "seq",
            "time_us",
            "kind",
            "active",
            "channel",
            "applied_override_cpct",
        ],
        FrameType::Heartbeat => &["seq", "time_us", "flags", "faults", "last_sample_seq"],
    }
}

/// `seq` and the sixteen values of a SimTruth.
const SIM_TRUTH_FIELDS: [&str; TRUTH_VALUES + 1] = {
    let mut names = ["seq"; TRUTH_VALUES + 1];
    let mut i = 0;
    while i < TRUTH_VALUES {
        names[i + 1] = SimTruth::NAMES[i];
        i += 1;
    }
    names
};

/// The fields that may be left out of an object: a `flags` or `faults` byte, which then has no
/// bit set (no feed hold, no state, no fault). Every other field is required: a value left out
/// is far more often a typo than a wish for zero, and a zero override is a feed stop.
pub const DEFAULT_ZERO_FIELDS: [&str; 2] = ["flags", "faults"];

/// Reads the fields of one object of a known frame type, naming the type and the field in
/// errors.
struct Fields<'a> {
    map: &'a Map<String, Value>,
    type_name: &'static str,
}

impl Fields<'_> {
    /// The value of field `name`: `None` only for the field that defaults to zero.
    fn get(&self, name: &str) -> Result<Option<&Value>, String> {
        match self.map.get(name) {
            Some(v) => Ok(Some(v)),
            None if DEFAULT_ZERO_FIELDS.contains(&name) => Ok(None),
            None => Err(format!("{}: missing field {name:?}", self.type_name)),
        }
    }

    fn bad(&self, name: &str, what: impl std::fmt::Display) -> String {
        format!("{}: {name}: {what}", self.type_name)
    }

    fn int<T: TryFrom<i64>>(&self, name: &str) -> Result<T, String> {
        match self.get(name)? {
            None => T::try_from(0).map_err(|_| self.bad(name, "out of range")),
            Some(v) => v.as_i64().and_then(|i| T::try_from(i).ok()).ok_or_else(|| {
                self.bad(
                    name,
                    format!("{} is not an integer in range", excerpt(&v.to_string())),
                )
            }),
        }
    }

    fn f32(&self, name: &str) -> Result<f32, String> {
        match self.get(name)? {
            None => Ok(0.0),
            Some(Value::Null) => Ok(f32::NAN),
            Some(v) => {
                let x = v.as_f64().ok_or_else(|| {
                    self.bad(name, format!("{} is not a number", excerpt(&v.to_string())))
                })?;
                // `as` would make it ±∞ on the wire.
                if x.abs() > f64::from(f32::MAX) {
                    return Err(self.bad(
                        name,
                        format!(
                            "{} is beyond the range of this 32-bit field (±{})",
                            crate::input::readable(x),
                            crate::input::readable(f64::from(f32::MAX))
                        ),
                    ));
                }
                Ok(x as f32)
            }
        }
    }

    fn ints<T: TryFrom<i64> + Copy + Default, const N: usize>(
        &self,
        name: &str,
    ) -> Result<[T; N], String> {
        let mut out = [T::default(); N];
        let Some(v) = self.get(name)? else {
            return Ok(out);
        };
        let items = v.as_array().filter(|a| a.len() == N).ok_or_else(|| {
            self.bad(
                name,
                format!(
                    "expected an array of {N} integers, got {}",
                    excerpt(&v.to_string())
                ),
            )
        })?;
        for (slot, item) in out.iter_mut().zip(items) {
            *slot = item
                .as_i64()
                .and_then(|i| T::try_from(i).ok())
                .ok_or_else(|| {
                    self.bad(
                        name,
                        format!("{} is not an integer in range", excerpt(&item.to_string())),
                    )
                })?;
        }
        Ok(out)
    }

    fn text<const N: usize>(&self, name: &str) -> Result<[u8; N], String> {
        match self.get(name)? {
            None => Ok([0; N]),
            // The wire pads text with zero bytes: a NUL inside would end it there.
            Some(Value::String(s)) if s.contains('\0') => Err(self.bad(
                name,
                format!(
                    "{} holds a NUL character, which would end the text on the wire",
                    excerpt(s)
                ),
            )),
            Some(Value::String(s)) if s.len() <= N => Ok(padded(s)),
            Some(Value::String(s)) => {
                Err(self.bad(name, format!("{} is longer than {N} bytes", excerpt(s))))
            }
            Some(_) => self.ints(name),
        }
    }

    /// A name from `names` (code, name) or a number.
    fn code(&self, name: &str, names: &[(u8, &str)]) -> Result<u8, String> {
        match self.get(name)? {
            None => Ok(0),
            Some(Value::String(s)) => names
                .iter()
                .find(|(_, n)| n == s)
                .map(|(c, _)| *c)
                .ok_or_else(|| {
                    let known: Vec<&str> = names.iter().map(|(_, n)| *n).collect();
                    self.bad(
                        name,
                        format!("unknown {}; known: {}", excerpt(s), known.join(", ")),
                    )
                }),
            Some(_) => self.int(name),
        }
    }
}

/// One line of JSON as a value, strictly: a key given twice in any object is an error (a
/// plain reading keeps the last, so a frame could go out with a value nobody meant).
///
/// ```
/// use cutlab::protocol::json::parse_line;
/// assert!(parse_line(r#"{"type": "arm", "seq": 1}"#).is_ok());
/// let e = parse_line(r#"{"type": "arm", "seq": 1, "seq": 2}"#).unwrap_err();
/// assert!(e.contains("\"seq\" is given twice"), "{e}");
/// ```
pub fn parse_line(text: &str) -> Result<Value, String> {
    serde_json::from_str::<Strict>(text)
        .map(|s| s.0)
        .map_err(|e| match e.classify() {
            serde_json::error::Category::Data => e.to_string(),
            _ => format!("not JSON: {e}"),
        })
}

/// A JSON value read with every object's keys checked for repeats.
struct Strict(Value);

impl<'de> Deserialize<'de> for Strict {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(StrictVisitor)
    }
}

struct StrictVisitor;

impl<'de> Visitor<'de> for StrictVisitor {
    type Value = Strict;

    fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Strict, E> {
        Ok(Strict(Value::Bool(v)))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Strict, E> {
        Ok(Strict(Value::from(v)))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Strict, E> {
        Ok(Strict(Value::from(v)))
    }

    fn visit_f64<E>(self, v: f64) -> Result<Strict, E> {
        Ok(Strict(Value::from(v)))
    }

    fn visit_str<E>(self, v: &str) -> Result<Strict, E> {
        Ok(Strict(Value::String(v.to_string())))
    }

    fn visit_string<E>(self, v: String) -> Result<Strict, E> {
        Ok(Strict(Value::String(v)))
    }

    fn visit_unit<E>(self) -> Result<Strict, E> {
        Ok(Strict(Value::Null))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Strict, A::Error> {
        let mut items = Vec::new();
        while let Some(Strict(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(Strict(Value::Array(items)))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut access: A) -> Result<Strict, A::Error> {
        let mut map = Map::new();
        while let Some(key) = access.next_key::<String>()? {
            if map.contains_key(&key) {
                return Err(de::Error::custom(format!(
                    "field {} is given twice",
                    excerpt(&key)
                )));
            }
            let Strict(value) = access.next_value()?;
            map.insert(key, value);
        }
        Ok(Strict(Value::Object(map)))
    }
}

/// The frame a JSON object describes.
pub fn frame_from_json(value: &Value) -> Result<Frame, String> {
    let map = value.as_object().ok_or_else(|| {
        format!(
            "expected a JSON object, got {}",
            excerpt(&value.to_string())
        )
    })?;
    let type_name = match map.get("type") {
        None => return Err("missing \"type\"".into()),
        Some(Value::String(name)) => name,
        Some(other) => {
            return Err(format!(
                "\"type\" must be a frame type's name, got {}",
                excerpt(&other.to_string())
            ))
        }
    };
    let frame_type = FrameType::from_name(type_name).ok_or_else(|| {
        let names: Vec<&str> = FrameType::ALL.iter().map(|t| t.name()).collect();
        format!(
            "unknown type {}; types: {}",
            excerpt(type_name),
            names.join(", ")
        )
    })?;
    let type_name = frame_type.name();
    let known = field_names(frame_type);
    let unknown: Vec<String> = map
        .keys()
        .filter(|k| k.as_str() != "type" && !known.contains(&k.as_str()))
        .map(|k| excerpt(k))
        .collect();
    if !unknown.is_empty() {
        // A few of them: an object of a million stray keys makes a short message.
        const SHOWN: usize = 5;
        let more = unknown.len().saturating_sub(SHOWN);
        return Err(format!(
            "{type_name}: unknown field{} {}{}; a {type_name} frame has {}",
            if unknown.len() > 1 { "s" } else { "" },
            unknown[..unknown.len().min(SHOWN)].join(", "),
            if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            },
            known.join(", ")
        ));
    }
    let f = Fields { map, type_name };
    let modes = [(0, "dial16"), (1, "whole-percent"), (2, "continuous")];
    let results = [
        (0, "applied"),
        (1, "limited"),
        (2, "not-armed"),
        (3, "refused"),
        (4, "stale"),
        (5, "cause-active"),
    ];
    let kinds = FaultKind::KNOWN.map(|k| (k.code(), k.name()));
    let commands: Vec<(u8, &str)> = FrameType::ALL
        .iter()
        .map(|t| (*t as u8, t.name()))
        .collect();
    Ok(match frame_type {
        FrameType::Hello => Frame::Hello(Hello {
            version_major: f.int("version_major")?,
            version_minor: f.int("version_minor")?,
        }),
        FrameType::Capabilities => Frame::Capabilities(Capabilities {
            version_major: f.int("version_major")?,
            version_minor: f.int("version_minor")?,
            device_id: f.text::<DEVICE_ID_LEN>("device_id")?,
            program: f.text::<PROGRAM_LEN>("program")?,
            channel_mask: f.int("channel_mask")?,
            spindle_current_a_per_count: f.f32("spindle_current_a_per_count")?,
            feed_current_a_per_count: f.f32("feed_current_a_per_count")?,
            fv_v_per_count: f.f32("fv_v_per_count")?,
            sample_rate_hz: f.f32("sample_rate_hz")?,
            override_mode: OverrideModeCode::from_code(f.code("override_mode", &modes)?),
            min_override_cpct: f.int("min_override_cpct")?,
            max_override_cpct: f.int("max_override_cpct")?,
            dial_cpct: f.ints("dial_cpct")?,
            watchdog_timeout_ms: f.int("watchdog_timeout_ms")?,
            fallback_override_cpct: f.int("fallback_override_cpct")?,
            over_current_a: f.f32("over_current_a")?,
            features: f.int("features")?,
            measured: f.int("measured")?,
            fallback_limit_ms: f.int("fallback_limit_ms")?,
            line_baud: f.int("line_baud")?,
        }),
        FrameType::Sample => Frame::Sample(Sample {
            seq: f.int("seq")?,
            time_us: f.int("time_us")?,
            flags: f.int("flags")?,
            spindle_current_counts: f.ints("spindle_current_counts")?,
            feed_current_counts: f.ints("feed_current_counts")?,
            fv_counts: f.int("fv_counts")?,
            spindle_speed_rpm: f.f32("spindle_speed_rpm")?,
            spindle_command_rpm: f.f32("spindle_command_rpm")?,
            programmed_feed_mm_min: f.f32("programmed_feed_mm_min")?,
            feed_mm_min: f.f32("feed_mm_min")?,
            applied_override_cpct: f.int("applied_override_cpct")?,
            dial_code: f.int("dial_code")?,
            faults: f.int("faults")?,
        }),
        FrameType::SimTruth => {
            let mut v = [0f32; TRUTH_VALUES];
            for (slot, name) in v.iter_mut().zip(SimTruth::NAMES) {
                *slot = f.f32(name)?;
            }
            Frame::SimTruth(SimTruth::from_values(f.int("seq")?, v))
        }
        FrameType::SetOverride => Frame::SetOverride(SetOverride {
            seq: f.int("seq")?,
            override_cpct: f.int("override_cpct")?,
            flags: f.int("flags")?,
            sample_time_us: f.int("sample_time_us")?,
        }),
        FrameType::Arm => Frame::Arm(Arm { seq: f.int("seq")? }),
        FrameType::Disarm => Frame::Disarm(Disarm { seq: f.int("seq")? }),
        FrameType::Reset => Frame::Reset(Reset { seq: f.int("seq")? }),
        FrameType::Ack => Frame::Ack(Ack {
            seq: f.int("seq")?,
            command: f.code("command", &commands)?,
            result: AckResult::from_code(f.code("result", &results)?),
            applied_override_cpct: f.int("applied_override_cpct")?,
            flags: f.int("flags")?,
        }),
        FrameType::Fault => Frame::Fault(Fault {
            seq: f.int("seq")?,
            time_us: f.int("time_us")?,
            kind: FaultKind::from_code(f.code("kind", &kinds)?),
            active: f.int("active")?,
            channel: f.int("channel")?,
            applied_override_cpct: f.int("applied_override_cpct")?,
        }),
        FrameType::Heartbeat => Frame::Heartbeat(Heartbeat {
            seq: f.int("seq")?,
            time_us: f.int("time_us")?,
            flags: f.int("flags")?,
            faults: f.int("faults")?,
            last_sample_seq: f.int("last_sample_seq")?,
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::frame::padded;

    fn zero_frame(t: FrameType) -> Frame {
        let payload = [0u8; 250];
        let mut p = payload;
        p[0] = t as u8;
        match Frame::read_payload(&p) {
            Ok(f) => f,
            Err(e) => panic!("{e}"),
        }
    }

    #[test]
    fn the_field_lists_are_the_keys_decode_prints() {
        for t in FrameType::ALL {
            let v = frame_to_json(&zero_frame(t));
            let mut printed: Vec<&str> = v
                .as_object()
                .unwrap()
                .keys()
                .map(String::as_str)
                .filter(|k| *k != "type")
                .collect();
            let mut listed = field_names(t).to_vec();
            printed.sort_unstable();
            listed.sort_unstable();
            assert_eq!(printed, listed, "{}", t.name());
        }
    }

    #[test]
    fn a_missing_field_is_an_error_naming_the_type_and_the_field() {
        let e =
            frame_from_json(&json!({"type": "set-override", "seq": 1, "flags": 0})).unwrap_err();
        assert_eq!(e, "set-override: missing field \"override_cpct\"");
        // Once an all-zero frame: now the first field it lacks.
        let e = frame_from_json(&json!({"type": "capabilities"})).unwrap_err();
        assert_eq!(e, "capabilities: missing field \"version_major\"");
        let e = frame_from_json(&json!({"type": "heartbeat", "seq": 3})).unwrap_err();
        assert_eq!(e, "heartbeat: missing field \"time_us\"");
    }

    #[test]
    fn an_unknown_field_is_an_error_listing_the_fields_of_the_type() {
        let e = frame_from_json(&json!({"type": "set-override", "seq": 1, "override_pct": 80}))
            .unwrap_err();
        assert_eq!(
            e,
            "set-override: unknown field \"override_pct\"; a set-override frame has seq, \
             override_cpct, flags, sample_time_us"
        );
        let e = frame_from_json(&json!({"type": "arm", "seq": 1, "a": 1, "b": 2})).unwrap_err();
        assert!(e.starts_with("arm: unknown fields \"a\", \"b\";"), "{e}");
    }

    #[test]
    fn what_the_wire_would_change_is_refused_and_a_bad_value_is_quoted_short() {
        // A 32-bit field beyond its range would go out as ±∞.
        let mut sample = frame_to_json(&zero_frame(FrameType::Sample));
        sample["feed_mm_min"] = json!(1e39);
        let e = frame_from_json(&sample).unwrap_err();
        assert_eq!(
            e,
            "sample: feed_mm_min: 1e39 is beyond the range of this 32-bit field (±3.4028e38)"
        );
        sample["feed_mm_min"] = json!(-3.0e38);
        assert!(frame_from_json(&sample).is_ok());
        // A NUL would end the device's name on the wire: "a\u0000b" came back as "a".
        let mut caps = frame_to_json(&zero_frame(FrameType::Capabilities));
        caps["device_id"] = json!("a\u{0}b");
        let e = frame_from_json(&caps).unwrap_err();
        assert!(
            e.contains("device_id: \"a\\0b\" holds a NUL character"),
            "{e}"
        );
        // A key given twice: a plain reading keeps the last.
        let e =
            parse_line(r#"{"type":"set-override","seq":1,"override_cpct":8000,"override_cpct":0}"#)
                .unwrap_err();
        assert!(
            e.starts_with("field \"override_cpct\" is given twice"),
            "{e}"
        );
        assert!(parse_line("{\"a\": [1, {\"b\": 2, \"b\": 3}]}").is_err());
        assert!(parse_line("nope").unwrap_err().starts_with("not JSON: "));
        // "type" that is not a string is said as such.
        assert_eq!(
            frame_from_json(&json!({"type": 1})).unwrap_err(),
            "\"type\" must be a frame type's name, got \"1\""
        );
        // A 10 MB value makes a short message.
        let huge = "x".repeat(10_000_000);
        let mut long_id = frame_to_json(&zero_frame(FrameType::Capabilities));
        long_id["device_id"] = json!(huge.clone());
        for v in [
            json!({"type": huge.clone()}),
            json!({"type": "arm", "seq": huge.clone()}),
            long_id,
            json!({"type": "arm", "seq": 1, huge.clone(): 1}),
            json!([huge.clone()]),
        ] {
            let e = frame_from_json(&v).unwrap_err();
            assert!(
                e.len() < 400 && e.contains("characters)"),
                "{}",
                &e[..e.len().min(400)]
            );
        }
    }

    #[test]
    fn only_a_flags_or_faults_byte_may_be_left_out_and_it_is_then_zero() {
        let f = frame_from_json(
            &json!({"type": "set-override", "seq": 1, "override_cpct": 8000, "sample_time_us": 5}),
        );
        assert_eq!(
            f,
            Ok(Frame::SetOverride(SetOverride {
                seq: 1,
                override_cpct: 8000,
                flags: 0,
                sample_time_us: 5,
            }))
        );
        let mut caps = frame_to_json(&zero_frame(FrameType::Capabilities));
        caps["device_id"] = json!("bridge");
        let Ok(Frame::Capabilities(c)) = frame_from_json(&caps) else {
            panic!("{caps}")
        };
        assert_eq!(c.device_id, padded::<DEVICE_ID_LEN>("bridge"));
        caps.as_object_mut().unwrap().remove("features");
        assert_eq!(
            frame_from_json(&caps).unwrap_err(),
            "capabilities: missing field \"features\""
        );
    }
}

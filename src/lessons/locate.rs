//! Where a field of a JSON text is: the line of the value at a path such as
//! `steps[2].check.conditions[0].metric`, so a lesson's semantic errors (an unknown metric, a bad
//! run query) name the line as serde_json's syntax and type errors do.
//!
//! serde_json keeps no positions in the values it reads, so this walks the text itself. It only
//! locates: the text has already been read by serde_json, and anything it cannot follow gives no
//! line rather than an error.

/// One step of a path: an object's field or an array's element.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PathPart {
    /// A field of an object.
    Field(String),
    /// An element of an array, from 0.
    Index(usize),
}

/// A path as lessons' messages write it: `steps[2].check.conditions[0].metric`.
pub fn path_text(path: &[PathPart]) -> String {
    let mut out = String::new();
    for part in path {
        match part {
            PathPart::Field(name) if out.is_empty() => out.push_str(name),
            PathPart::Field(name) => {
                out.push('.');
                out.push_str(name);
            }
            PathPart::Index(i) => out.push_str(&format!("[{i}]")),
        }
    }
    out
}

/// The line (from 1) where the value at `path` starts in `json`, or the line of the deepest
/// part of the path that exists (a missing field is reported on its object's line).
///
/// ```
/// use cutlab::lessons::locate::{line_of, PathPart};
/// let json = "{\n  \"steps\": [\n    {\"a\": 1},\n    {\n      \"b\": 2\n    }\n  ]\n}";
/// let path = [PathPart::Field("steps".into()), PathPart::Index(1), PathPart::Field("b".into())];
/// assert_eq!(line_of(json, &path), 5);
/// ```
pub fn line_of(json: &str, path: &[PathPart]) -> usize {
    let bytes = json.as_bytes();
    let mut cursor = Cursor { bytes, at: 0 };
    cursor.skip_space();
    for part in path {
        let found = cursor.at;
        let next = match (part, cursor.peek()) {
            (PathPart::Field(name), Some(b'{')) => cursor.field(name),
            (PathPart::Index(i), Some(b'[')) => cursor.element(*i),
            _ => None,
        };
        match next {
            Some(at) => cursor.at = at,
            None => return line_at(json, found),
        }
    }
    line_at(json, cursor.at)
}

fn line_at(json: &str, at: usize) -> usize {
    1 + json.as_bytes()[..at.min(json.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn peek(&self) -> Option<u8> {
        self.bytes.get(self.at).copied()
    }

    fn skip_space(&mut self) {
        while self.peek().is_some_and(|b| b.is_ascii_whitespace()) {
            self.at += 1;
        }
    }

    /// Reads a string starting at the cursor's quote; returns its raw text (escapes kept).
    fn string(&mut self) -> Option<&[u8]> {
        if self.peek() != Some(b'"') {
            return None;
        }
        let start = self.at + 1;
        let mut i = start;
        while let Some(&b) = self.bytes.get(i) {
            match b {
                b'\\' => i += 2,
                b'"' => {
                    self.at = i + 1;
                    return self.bytes.get(start..i);
                }
                _ => i += 1,
            }
        }
        None
    }

    /// Skips one value of any kind.
    fn skip_value(&mut self) -> Option<()> {
        self.skip_space();
        match self.peek()? {
            b'"' => self.string().map(|_| ()),
            open @ (b'{' | b'[') => {
                let close = if open == b'{' { b'}' } else { b']' };
                self.at += 1;
                loop {
                    self.skip_space();
                    match self.peek()? {
                        b if b == close => {
                            self.at += 1;
                            return Some(());
                        }
                        b',' | b':' => self.at += 1,
                        _ => self.skip_value()?,
                    }
                }
            }
            _ => {
                while self
                    .peek()
                    .is_some_and(|b| !matches!(b, b',' | b'}' | b']') && !b.is_ascii_whitespace())
                {
                    self.at += 1;
                }
                Some(())
            }
        }
    }

    /// The position of the value of field `name` in the object at the cursor.
    fn field(&mut self, name: &str) -> Option<usize> {
        self.at += 1;
        loop {
            self.skip_space();
            match self.peek()? {
                b'}' => return None,
                b',' => self.at += 1,
                b'"' => {
                    let key = self.string()?.to_vec();
                    self.skip_space();
                    if self.peek()? != b':' {
                        return None;
                    }
                    self.at += 1;
                    self.skip_space();
                    if key == name.as_bytes() {
                        return Some(self.at);
                    }
                    self.skip_value()?;
                }
                _ => return None,
            }
        }
    }

    /// The position of element `index` of the array at the cursor.
    fn element(&mut self, index: usize) -> Option<usize> {
        self.at += 1;
        let mut seen = 0;
        loop {
            self.skip_space();
            match self.peek()? {
                b']' => return None,
                b',' => self.at += 1,
                _ if seen == index => return Some(self.at),
                _ => {
                    self.skip_value()?;
                    seen += 1;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(name: &str) -> PathPart {
        PathPart::Field(name.to_string())
    }

    #[test]
    fn a_field_inside_nested_arrays_is_found_on_its_line() {
        let json = r#"{
  "id": "x",
  "steps": [
    { "check": { "conditions": [ {"metric": "a"},
        {"metric": "b", "value": 3} ] } }
  ]
}"#;
        let path = [
            field("steps"),
            PathPart::Index(0),
            field("check"),
            field("conditions"),
            PathPart::Index(1),
            field("value"),
        ];
        assert_eq!(line_of(json, &path), 5);
        assert_eq!(path_text(&path), "steps[0].check.conditions[1].value");
    }

    #[test]
    fn strings_with_braces_and_escaped_quotes_do_not_mislead_it() {
        let json = "{\"a\": \"}\\\"{[\",\n\"b\": 1}";
        assert_eq!(line_of(json, &[field("b")]), 2);
    }

    #[test]
    fn a_missing_field_is_reported_on_its_objects_line() {
        let json = "{\n\"steps\": [\n{\"x\": 1}\n]}";
        let path = [field("steps"), PathPart::Index(0), field("title")];
        assert_eq!(line_of(json, &path), 3);
    }
}

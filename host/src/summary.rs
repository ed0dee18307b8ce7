//! The one-screen summary a command prints when it is done.

use std::fmt;

/// A titled list of `key: value` lines; stages append their own lines.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// First line.
    pub title: String,
    /// `(key, value)` lines in order.
    pub lines: Vec<(String, String)>,
    /// When set, printed instead of the title and lines (e.g. JSON).
    pub raw: Option<String>,
}

impl Summary {
    /// An empty summary with a title.
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            lines: Vec::new(),
            raw: None,
        }
    }

    /// Appends one line.
    pub fn push(&mut self, key: impl Into<String>, value: impl fmt::Display) {
        self.lines.push((key.into(), value.to_string()));
    }

    /// The value of the first line with `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.lines
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(raw) = &self.raw {
            return writeln!(f, "{raw}");
        }
        writeln!(f, "{}", self.title)?;
        let width = self.lines.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
        for (k, v) in &self.lines {
            writeln!(f, "  {k:<width$}  {v}")?;
        }
        Ok(())
    }
}

/// `part` as a percentage of `whole` with one decimal ("0.0" for an empty whole).
pub fn percent(part: usize, whole: usize) -> String {
    if whole == 0 {
        return "0.0".into();
    }
    format!("{:.1}", 100.0 * part as f64 / whole as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_aligned() {
        let mut s = Summary::new("t");
        s.push("a", 1);
        s.push("long key", "x");
        assert_eq!(s.to_string(), "t\n  a         1\n  long key  x\n");
        assert_eq!(s.get("a"), Some("1"));
        assert_eq!(percent(1, 3), "33.3");
        assert_eq!(percent(1, 0), "0.0");
    }
}

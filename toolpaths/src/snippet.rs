//! Spindle snippets (the configured lines that turn a brush motor on and off): the word-by-
//! word check of what they may hold, and the dwell they add to a program's cycle time.

use crate::error::{Result, ToolpathError};

/// LinuxCNC comments that do something (print, log to a file, probe to a file).
const ACTIVE_COMMENTS: [&str; 10] = [
    "MSG",
    "DEBUG",
    "PRINT",
    "LOG",
    "LOGOPEN",
    "LOGAPPEND",
    "LOGCLOSE",
    "PROBEOPEN",
    "PROBECLOSE",
    "ABORT",
];

/// A G-code number as rs274 reads it: optional sign, digits with an optional point.
fn gnum(s: &str) -> Option<f64> {
    let t = s.strip_prefix(['+', '-']).unwrap_or(s);
    let ok = !t.is_empty()
        && t != "."
        && t.chars().all(|c| c.is_ascii_digit() || c == '.')
        && t.matches('.').count() <= 1;
    if ok {
        s.parse().ok().filter(|v: &f64| v.is_finite())
    } else {
        None
    }
}

/// The words of one trimmed snippet line (comments dropped), or the offending text and why.
fn split_words(line: &str) -> std::result::Result<Vec<&str>, (&str, &'static str)> {
    let mut words = Vec::new();
    let mut rest = line;
    while !rest.is_empty() {
        let c = rest.chars().next().unwrap_or(' ');
        if c.is_whitespace() {
            rest = rest.trim_start();
        } else if c == ';' {
            break;
        } else if c == '(' {
            let Some(end) = rest.find(')') else {
                return Err((rest, "unclosed comment"));
            };
            let body = &rest[1..end];
            if body.contains('(') {
                return Err((&rest[..=end], "nested comment"));
            }
            let first: String = body
                .trim_start()
                .chars()
                .take_while(|c| c.is_ascii_alphabetic())
                .collect::<String>()
                .to_ascii_uppercase();
            if ACTIVE_COMMENTS.contains(&first.as_str()) {
                return Err((&rest[..=end], "active comment"));
            }
            rest = &rest[end + 1..];
        } else if c.is_ascii_alphabetic() {
            let end = rest[1..]
                .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == '+' || c == '-'))
                .map_or(rest.len(), |e| e + 1);
            words.push(&rest[..end]);
            rest = &rest[end..];
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            return Err((&rest[..end], "the word"));
        }
    }
    Ok(words)
}

/// Check a snippet word by word (see [`Spindle::Snippet`](crate::Spindle::Snippet)).
pub(crate) fn check_snippet(key: &'static str, text: &str) -> Result<()> {
    let allowed = "only M3, M4, M5, M7, M8, M9, S<number>, G4 P<number> and comments are \
                   allowed in a snippet";
    for (li, raw) in text.lines().enumerate() {
        let line = raw.trim();
        let bad = |word: &str, why: &str| ToolpathError::Gcode {
            key,
            message: format!("line {} `{}`: {why} `{word}`; {allowed}", li + 1, short_line(line)),
        };
        let words = split_words(line).map_err(|(w, why)| bad(w, why))?;
        let (mut spindle, mut coolant, mut s, mut dwell, mut p) = (0, 0, 0, 0, 0);
        for w in words {
            let letter = w.chars().next().unwrap_or(' ').to_ascii_uppercase();
            let Some(v) = gnum(&w[1..]) else {
                return Err(bad(w, "the word"));
            };
            match letter {
                'M' if [3.0, 4.0, 5.0].contains(&v) => spindle += 1,
                'M' if [7.0, 8.0, 9.0].contains(&v) => coolant += 1,
                'S' if v >= 0.0 => s += 1,
                'G' if v == 4.0 => dwell += 1,
                'P' if v >= 0.0 => p += 1,
                _ => return Err(bad(w, "the word")),
            }
            let twice = match letter {
                'M' if spindle > 1 => Some("a second spindle word"),
                'M' if coolant > 1 => Some("a second coolant word"),
                'S' if s > 1 => Some("a second S word"),
                'G' if dwell > 1 => Some("a second dwell"),
                'P' if p > 1 => Some("a second P word"),
                _ => None,
            };
            if let Some(why) = twice {
                return Err(bad(w, &format!("{why} on the line:")));
            }
        }
        if dwell != p {
            let w = if dwell > 0 { "G4" } else { "P" };
            return Err(bad(w, "a dwell needs `G4 P<seconds>` on one line, got"));
        }
    }
    Ok(())
}

/// Seconds of dwell (`G4 P<seconds>`) in a snippet: the sum of its `P` words. A snippet
/// that [`check_snippet`] accepts holds `P` only beside `G4`; unreadable words count 0.
pub(crate) fn snippet_dwell(text: &str) -> f64 {
    text.lines()
        .filter_map(|l| split_words(l.trim()).ok())
        .flatten()
        .filter(|w| w.starts_with(['P', 'p']))
        .filter_map(|w| gnum(&w[1..]))
        .filter(|v| *v >= 0.0)
        .sum()
}

fn short_line(l: &str) -> String {
    let mut s: String = l.chars().take(80).collect();
    if l.chars().count() > 80 {
        s.push('…');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dwell_sums_p_words_and_skips_comments() {
        assert_eq!(snippet_dwell("M3 S9000\nG4 P1.5 (spin up, P9)\n; P7\nG4 P0.25"), 1.75);
        assert_eq!(snippet_dwell("M5"), 0.0);
        assert!(check_snippet("k", "G4 P1.5 (spin up)").is_ok());
        assert!(check_snippet("k", "G0 X1").is_err());
    }
}

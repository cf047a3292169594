//! Names and groups as trainees type them, made safe to show (issue 29: a 64-character
//! wide-glyph name pushed every roster row's buttons off a 1400 px window, an RTL override
//! displayed reversed, a name with newlines hid the trainee's attempts).
//!
//! [`display_name`] is applied once, on entry (`POST /api/sessions`): Unicode NFC (so the
//! same name typed two ways is one trainee); control characters become spaces and runs of
//! white space one space, trimmed; the bidirectional controls (embeddings, overrides,
//! isolates and marks: U+202A–U+202E, U+2066–U+2069, U+200E, U+200F, U+061C) are removed;
//! then it is cut to [`MAX_WIDTH`] terminal columns (East Asian wide characters count two,
//! `unicode-width`) with `…` where it was cut.

use unicode_normalization::UnicodeNormalization;
use unicode_width::UnicodeWidthChar;

/// The widest a name or group may be, in columns (a wide character is two).
pub const MAX_WIDTH: usize = 40;

/// Whether `c` is a bidirectional formatting control.
fn is_bidi_control(c: char) -> bool {
    matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}' | '\u{200E}' | '\u{200F}' | '\u{061C}')
}

/// `raw` as it is stored and shown (see the module doc).
pub fn display_name(raw: &str) -> String {
    display_text(raw, MAX_WIDTH)
}

/// The widest an assessor's note on a sign-off may be, in columns.
pub const NOTE_WIDTH: usize = 280;

/// `raw` cleaned as [`display_name`] cleans a name, cut to `max_width` columns (a sign-off's
/// note: [`NOTE_WIDTH`]).
pub fn display_text(raw: &str, max_width: usize) -> String {
    let mut clean = String::with_capacity(raw.len());
    for c in raw.nfc() {
        if is_bidi_control(c) {
            continue;
        }
        let c = if c.is_control() || c.is_whitespace() {
            ' '
        } else {
            c
        };
        if c == ' ' && (clean.is_empty() || clean.ends_with(' ')) {
            continue;
        }
        clean.push(c);
    }
    let clean = clean.trim_end();
    let mut out = String::with_capacity(clean.len());
    let mut width = 0;
    for c in clean.chars() {
        let w = c.width().unwrap_or(0);
        if width + w > max_width {
            // room for the ellipsis (one column)
            while width + 1 > max_width {
                let Some(last) = out.pop() else { break };
                width -= last.width().unwrap_or(0);
            }
            out.truncate(out.trim_end().len());
            out.push('…');
            return out;
        }
        width += w;
        out.push(c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn width(s: &str) -> usize {
        s.chars().map(|c| c.width().unwrap_or(0)).sum()
    }

    /// The hostile names, and the invariants: no control or bidi character is left,
    /// the width is at most [`MAX_WIDTH`], ordinary names pass unchanged.
    #[test]
    fn hostile_names_are_cleaned_and_ordinary_ones_kept() {
        assert_eq!(display_name("Ada Lovelace"), "Ada Lovelace");
        assert_eq!(display_name("  Ada\n\nLovelace\t"), "Ada Lovelace");
        assert_eq!(display_name("\u{202E}evil\u{202C}.exe"), "evil.exe");
        assert_eq!(display_name("a\u{0}b\u{1b}[31mc\rd"), "a b [31mc d");
        // NFC: e + combining acute is é
        assert_eq!(display_name("Rene\u{301}e"), "Ren\u{e9}e");
        // 64 wide glyphs (128 columns) are cut to 40 columns with the ellipsis
        let wide: String = std::iter::repeat_n('漢', 64).collect();
        let w = display_name(&wide);
        assert!(w.ends_with('…'), "{w}");
        assert!(width(&w) <= MAX_WIDTH, "{} columns", width(&w));
        assert_eq!(w.chars().filter(|&c| c == '漢').count(), 19);
        let long = "x".repeat(64);
        assert_eq!(
            display_name(&long),
            format!("{}…", "x".repeat(MAX_WIDTH - 1))
        );
        for s in [
            wide.as_str(),
            "\u{2066}a\u{2069}\u{200f}",
            "\u{61c}\u{200e}",
        ] {
            let d = display_name(s);
            assert!(
                !d.chars().any(|c| c.is_control() || is_bidi_control(c)),
                "{d:?}"
            );
        }
        assert_eq!(display_name("\n\t "), "");
    }

    /// A sign-off's note is cleaned as a name is but keeps up to [`NOTE_WIDTH`] columns: a
    /// 300-character note is cut to 279 characters and the ellipsis (280 columns, counted by
    /// hand: one column each), a newline becomes a space.
    #[test]
    fn a_note_is_cleaned_like_a_name_and_cut_at_its_own_width() {
        assert_eq!(display_text("good\ncontrol ", NOTE_WIDTH), "good control");
        let long = "y".repeat(300);
        assert_eq!(
            display_text(&long, NOTE_WIDTH),
            format!("{}…", "y".repeat(279))
        );
        assert_eq!(display_text(&"y".repeat(280), NOTE_WIDTH), "y".repeat(280));
    }
}

//! Words for users: typo suggestions for names they type (option keys, parameters, outputs,
//! prompt words) and the form numbers take in messages.

/// The known name closest to `word` by edit distance, if it is plausibly a typo of it.
pub fn nearest<'a>(word: &str, known: &[&'a str]) -> Option<&'a str> {
    known
        .iter()
        .map(|k| (edit_distance(word, k), *k))
        .filter(|(d, k)| *d <= 2.max(k.len() / 3))
        .min()
        .map(|(_, k)| k)
}

/// Levenshtein distance in characters.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let next = (prev + usize::from(ca != cb))
                .min(row[j] + 1)
                .min(row[j + 1] + 1);
            prev = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// A user's number as messages show it: Rust's shortest round-trip form, switching to
/// exponent notation for very large or very small magnitudes (so 1e308 prints as `1e308`, not
/// as 309 digits).
pub fn number(x: f64) -> String {
    let magnitude = x.abs();
    if x.is_finite() && magnitude != 0.0 && !(1e-5..1e15).contains(&magnitude) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `text` with every number written out in more than 17 significant digits (what a value
/// like 1e300 becomes through `{}`) put in the short form of [`number`]. Messages are made in
/// many layers; this keeps all of them short where they are shown. Digit runs that touch
/// letters (hashes, names) are left alone.
pub fn short_numbers(text: &str) -> std::borrow::Cow<'_, str> {
    let bytes = text.as_bytes();
    let mut out = String::new();
    let (mut copied, mut i) = (0, 0);
    while i < bytes.len() {
        let start = i;
        let word_before =
            start > 0 && (bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_');
        let mut end = start;
        while end < bytes.len() && (bytes[end].is_ascii_digit() || bytes[end] == b'.') {
            end += 1;
        }
        if end == start {
            i += 1;
            continue;
        }
        let word_after =
            end < bytes.len() && (bytes[end].is_ascii_alphanumeric() || bytes[end] == b'_');
        let token = text[start..end].trim_end_matches('.');
        let digits = token.bytes().filter(u8::is_ascii_digit).count();
        // Whole numbers up to 20 digits may be exact integers (u64 seeds): kept as written.
        let long = if token.contains('.') {
            digits > 17
        } else {
            digits > 20
        };
        if let (false, false, true, Ok(x)) = (word_before, word_after, long, token.parse::<f64>()) {
            out.push_str(&text[copied..start]);
            out.push_str(&number(x));
            copied = end;
        }
        i = end;
    }
    if copied == 0 {
        return text.into();
    }
    out.push_str(&text[copied..]);
    out.into()
}

/// `text` cut to its first `max` characters, saying how much was left out, so that a huge
/// value or source line cannot flood a message.
pub fn clip(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(max) {
        None => text.into(),
        Some((end, _)) => format!("{}… ({} more bytes)", &text[..end], text.len() - end).into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typo_suggestions() {
        assert_eq!(nearest("pich", &["pitch", "yaw", "roll"]), Some("pitch"));
        assert_eq!(nearest("zzzzzz", &["pitch", "yaw"]), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn long_numbers_in_finished_messages_are_shortened() {
        let long = format!("height = {} m must lie inside the shell", 1e300);
        assert_eq!(
            short_numbers(&long),
            "height = 1e300 m must lie inside the shell"
        );
        let negative = format!("at ({}, 0, {}) m", -1e25, 2.5e-30);
        assert_eq!(short_numbers(&negative), "at (-1e25, 0, 2.5e-30) m");
        let tiny = format!("{}", 1.5e-20);
        assert_eq!(short_numbers(&tiny), "1.5e-20");
        for kept in [
            "sample 123456 of 1000000",
            "seed 18446744073709551615",
            "hash 0123456789012345678901234abc",
            "0.30000000000000004",
            "file_123456789012345678901",
            "done.",
        ] {
            assert_eq!(short_numbers(kept), kept);
        }
    }

    #[test]
    fn numbers_in_messages_stay_short() {
        assert_eq!(number(1e308), "1e308");
        assert_eq!(number(-f64::MAX), "-1.7976931348623157e308");
        assert_eq!(number(5e-324), "5e-324");
        assert_eq!(number(1e15), "1e15");
        for (x, shown) in [
            (0.0, "0"),
            (0.25, "0.25"),
            (-3.0, "-3"),
            (123456.5, "123456.5"),
        ] {
            assert_eq!(number(x), shown);
        }
        assert_eq!(number(0.00001), "0.00001");
        assert_eq!(number(f64::NAN), "NaN");
        assert_eq!(number(f64::NEG_INFINITY), "-inf");
    }

    #[test]
    fn long_text_is_clipped_on_a_character_boundary() {
        assert_eq!(clip("short", 5), "short");
        assert_eq!(clip("ééé", 1), "é… (4 more bytes)");
    }
}

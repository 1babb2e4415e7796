//! Import warnings, collected once per kind with the first occurrence and a count.

/// Warnings by kind, in the order in which each kind first occurred.
#[derive(Default)]
pub(super) struct Warnings {
    /// `(kind, detail of the first occurrence, number of occurrences)`.
    kinds: Vec<(String, String, usize)>,
}

impl Warnings {
    /// Records one occurrence of `kind`; `detail` (which object, may be empty) is kept for
    /// the first occurrence only.
    pub(super) fn warn(&mut self, kind: impl Into<String>, detail: impl Into<String>) {
        let kind = kind.into();
        if let Some(entry) = self.kinds.iter_mut().find(|(k, _, _)| *k == kind) {
            entry.2 += 1;
        } else {
            self.kinds.push((kind, detail.into(), 1));
        }
    }

    /// One line per kind: `"<kind> (first: <detail>; <n> occurrences)"`, the parts that
    /// apply.
    pub(super) fn finish(self) -> Vec<String> {
        self.kinds
            .into_iter()
            .map(|(kind, first, count)| {
                let mut s = kind;
                if !first.is_empty() {
                    s.push_str(&format!(" (first: {first}"));
                    if count > 1 {
                        s.push_str(&format!("; {} occurrences", count));
                    }
                    s.push(')');
                } else if count > 1 {
                    s.push_str(&format!(" ({count} occurrences)"));
                }
                s
            })
            .collect()
    }
}

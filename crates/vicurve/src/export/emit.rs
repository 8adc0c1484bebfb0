//! Writing DXF tags: a group code on one line, its value on the next.

/// The shortest decimal text that reads back as the same `f64`, always
/// with a decimal point (`1.0`, not `1`) and never in exponent form, which
/// every DXF reader accepts. Non-finite values (never written by the
/// exporters, which check their input) become `0.0`.
pub fn fmt_f64(v: f64) -> String {
    if !v.is_finite() {
        return "0.0".into();
    }
    // Display of f64 is the shortest round-trip form, without exponent.
    let s = format!("{v}");
    if s.contains('.') {
        s
    } else {
        s + ".0"
    }
}

/// A DXF document being written.
#[derive(Default)]
pub struct Tags {
    out: String,
}

impl Tags {
    /// A tag with a text value; the group code right-aligned on 3
    /// characters as AutoCAD writes it.
    pub fn tag(&mut self, code: u16, value: &str) -> &mut Self {
        self.out.push_str(&format!("{code:>3}\n{value}\n"));
        self
    }

    /// An integer tag.
    pub fn int(&mut self, code: u16, value: i64) -> &mut Self {
        self.tag(code, &value.to_string())
    }

    /// A real tag.
    pub fn real(&mut self, code: u16, value: f64) -> &mut Self {
        self.tag(code, &fmt_f64(value))
    }

    /// A 3-D point `(x, y, 0)`: codes `code`, `code + 10`, `code + 20`.
    pub fn point(&mut self, code: u16, p: [f64; 2]) -> &mut Self {
        self.point3(code, [p[0], p[1], 0.0])
    }

    /// A 3-D point.
    pub fn point3(&mut self, code: u16, p: [f64; 3]) -> &mut Self {
        self.real(code, p[0])
            .real(code + 10, p[1])
            .real(code + 20, p[2])
    }

    /// A 2-D point: codes `code` and `code + 10`.
    pub fn point2(&mut self, code: u16, p: [f64; 2]) -> &mut Self {
        self.real(code, p[0]).real(code + 10, p[1])
    }

    /// A header variable name (group 9); its value follows.
    pub fn var(&mut self, name: &str) -> &mut Self {
        self.tag(9, name)
    }

    /// A comment line (group 999), which readers skip.
    pub fn comment(&mut self, text: &str) -> &mut Self {
        let one_line: String = text
            .chars()
            .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
            .collect();
        self.tag(999, &one_line)
    }

    /// `0 SECTION / 2 name`.
    pub fn section(&mut self, name: &str) -> &mut Self {
        self.tag(0, "SECTION").tag(2, name)
    }

    /// `0 ENDSEC`.
    pub fn end_section(&mut self) -> &mut Self {
        self.tag(0, "ENDSEC")
    }

    /// The text written.
    pub fn finish(self) -> String {
        self.out
    }
}

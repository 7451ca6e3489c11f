//! A small JSON reader for material files written by other tools: numbers, strings, arrays,
//! objects, true/false/null, and `//` or `/* */` comments (ARCSim's reader, jsoncpp, accepts
//! them and its own files use them). Errors name the line.

use std::collections::BTreeMap;

/// A parsed JSON value.
#[derive(Clone, Debug, PartialEq)]
pub enum Json {
    Null,
    Bool(bool),
    Number(f64),
    Text(String),
    Array(Vec<Json>),
    Object(BTreeMap<String, Json>),
}

/// Parses one JSON document.
pub fn parse(text: &str) -> Result<Json, String> {
    let mut p = Parser {
        s: text.as_bytes(),
        i: 0,
    };
    let v = p.value()?;
    p.blank()?;
    if p.i < p.s.len() {
        return Err(p.error("text after the end of the document"));
    }
    Ok(v)
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn error(&self, what: &str) -> String {
        let line = 1 + self.s[..self.i.min(self.s.len())]
            .iter()
            .filter(|&&c| c == b'\n')
            .count();
        format!("line {line}: {what}")
    }

    /// Skips white space and comments.
    fn blank(&mut self) -> Result<(), String> {
        loop {
            match self.s.get(self.i..self.i + 2) {
                Some(b"//") => {
                    while self.i < self.s.len() && self.s[self.i] != b'\n' {
                        self.i += 1;
                    }
                }
                Some(b"/*") => {
                    let end = self.s[self.i + 2..].windows(2).position(|w| w == b"*/");
                    match end {
                        Some(k) => self.i += k + 4,
                        None => return Err(self.error("unterminated comment")),
                    }
                }
                _ => match self.s.get(self.i) {
                    Some(c) if c.is_ascii_whitespace() => self.i += 1,
                    _ => return Ok(()),
                },
            }
        }
    }

    fn value(&mut self) -> Result<Json, String> {
        self.blank()?;
        match self.s.get(self.i) {
            None => Err(self.error("unexpected end of the document")),
            Some(b'{') => self.object(),
            Some(b'[') => self.array(),
            Some(b'"') => self.text().map(Json::Text),
            Some(_) => self.word(),
        }
    }

    fn object(&mut self) -> Result<Json, String> {
        self.i += 1;
        let mut map = BTreeMap::new();
        loop {
            self.blank()?;
            if self.s.get(self.i) == Some(&b'}') {
                self.i += 1;
                return Ok(Json::Object(map));
            }
            if !map.is_empty() {
                self.expect(b',')?;
                self.blank()?;
            }
            let key = self.text()?;
            self.blank()?;
            self.expect(b':')?;
            let v = self.value()?;
            map.insert(key, v);
        }
    }

    fn array(&mut self) -> Result<Json, String> {
        self.i += 1;
        let mut items = Vec::new();
        loop {
            self.blank()?;
            if self.s.get(self.i) == Some(&b']') {
                self.i += 1;
                return Ok(Json::Array(items));
            }
            if !items.is_empty() {
                self.expect(b',')?;
            }
            items.push(self.value()?);
        }
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if self.s.get(self.i) == Some(&c) {
            self.i += 1;
            Ok(())
        } else {
            Err(self.error(&format!("expected '{}'", c as char)))
        }
    }

    fn text(&mut self) -> Result<String, String> {
        self.expect(b'"')?;
        let start = self.i;
        while let Some(&c) = self.s.get(self.i) {
            match c {
                b'"' => {
                    self.i += 1;
                    return Ok(String::from_utf8_lossy(&self.s[start..self.i - 1]).into());
                }
                b'\\' => self.i += 2,
                _ => self.i += 1,
            }
        }
        Err(self.error("unterminated string"))
    }

    fn word(&mut self) -> Result<Json, String> {
        let start = self.i;
        while let Some(&c) = self.s.get(self.i) {
            if c.is_ascii_alphanumeric() || matches!(c, b'+' | b'-' | b'.') {
                self.i += 1;
            } else {
                break;
            }
        }
        let w = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
        match w {
            "true" => Ok(Json::Bool(true)),
            "false" => Ok(Json::Bool(false)),
            "null" => Ok(Json::Null),
            _ => w
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .map(Json::Number)
                .ok_or_else(|| {
                    self.i = start;
                    self.error(&format!("expected a value, got '{w}'"))
                }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_nested_numbers_comments_and_names_the_line_of_an_error() {
        let v = parse("{ // a comment\n \"a\": [1, -2.5e3, [0]], /* x */ \"b\": true }").unwrap();
        let Json::Object(m) = v else { panic!() };
        assert_eq!(
            m["a"],
            Json::Array(vec![
                Json::Number(1.0),
                Json::Number(-2500.0),
                Json::Array(vec![Json::Number(0.0)])
            ])
        );
        assert_eq!(m["b"], Json::Bool(true));
        let e = parse("{\n\"a\": [1,\n 2 3]}").unwrap_err();
        assert!(e.starts_with("line 3:"), "{e}");
        assert!(parse("{\"a\": nan}").is_err());
        assert!(parse("[1] 2").is_err());
    }
}

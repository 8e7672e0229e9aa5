//! `report.html`: one self-contained page, readable offline. Charts are
//! inline SVG, pictures are PNGs in `data:` URIs, the style sheet is
//! inline; nothing is fetched and no script runs.
//!
//! The page is built from [`Block`]s in order, so the build decides what
//! it says and this file only decides how it looks. Every text goes
//! through [`escape`]; SVG is trusted (it comes from [`crate::chart`]).

use std::fmt::Write as _;

use base64::Engine as _;

/// A rendered picture with its caption.
pub struct Picture {
    pub caption: String,
    pub png: Vec<u8>,
}

/// A table: column headers, each with the one line that explains it, and
/// rows of cells (already formatted).
pub struct Table {
    pub columns: Vec<(String, String)>,
    pub rows: Vec<Vec<String>>,
}

/// One piece of the page.
pub enum Block {
    /// A section heading.
    Heading(String),
    /// A paragraph of plain text.
    Text(String),
    /// Pictures side by side, in one row that wraps.
    Gallery(Vec<Picture>),
    /// An inline SVG document (a chart or a scale).
    Svg(String),
    /// A table with its column explanations below it.
    Table(Table),
    /// Content that varies from run to run (timings), marked so that
    /// digests can leave it out: it sits between `<!-- varies -->` and
    /// `<!-- /varies -->`.
    Varies(Vec<Block>),
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}\
th{background:#f2f2f2}td:nth-child(1){text-align:left}figure{display:inline-block;margin:4px;text-align:center}\
figcaption{font-size:small;max-width:256px}img{border:1px solid #ddd}dl{font-size:small}dt{font-weight:bold;float:left;margin-right:0.5em}\
dd{margin:0 0 0.2em 0}";

/// The whole page for `title` and `blocks`.
pub fn page(title: &str, blocks: &[Block]) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n\
         <style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
        escape(title),
        escape(title)
    );
    for b in blocks {
        block(&mut h, b);
    }
    h.push_str("</body>\n</html>\n");
    h
}

fn block(h: &mut String, b: &Block) {
    match b {
        Block::Heading(t) => {
            let _ = writeln!(h, "<h2>{}</h2>", escape(t));
        }
        Block::Text(t) => {
            let _ = writeln!(h, "<p>{}</p>", escape(t));
        }
        Block::Gallery(pics) => {
            h.push_str("<div class=\"gallery\">\n");
            for p in pics {
                let _ = writeln!(
                    h,
                    "<figure><img src=\"data:image/png;base64,{}\" alt=\"{}\" width=\"256\" height=\"256\">\
                     <figcaption>{}</figcaption></figure>",
                    base64::engine::general_purpose::STANDARD.encode(&p.png),
                    escape(&p.caption),
                    escape(&p.caption)
                );
            }
            h.push_str("</div>\n");
        }
        Block::Svg(svg) => {
            let body = svg
                .trim_start_matches("<?xml version=\"1.0\" encoding=\"UTF-8\"?>")
                .trim();
            let _ = writeln!(h, "<div class=\"chart\">{body}</div>");
        }
        Block::Table(t) => {
            h.push_str("<table>\n<tr>");
            for (c, _) in &t.columns {
                let _ = write!(h, "<th>{}</th>", escape(c));
            }
            h.push_str("</tr>\n");
            for r in &t.rows {
                h.push_str("<tr>");
                for c in r {
                    let _ = write!(h, "<td>{}</td>", escape(c));
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n<dl>\n");
            for (c, why) in &t.columns {
                let _ = writeln!(h, "<dt>{}</dt><dd>{}</dd>", escape(c), escape(why));
            }
            h.push_str("</dl>\n");
        }
        Block::Varies(inner) => {
            h.push_str("<!-- varies -->\n");
            for b in inner {
                block(h, b);
            }
            h.push_str("<!-- /varies -->\n");
        }
    }
}

/// `s` with `&`, `<`, `>`, `"` and `'` escaped for HTML text and
/// attributes.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// A horizontal colour bar for a heat map: `colour(t)` for `t` in `[0, 1]`
/// from left to right, labelled `low` and `high` at its ends.
pub fn colour_bar(colour: impl Fn(f32) -> [u8; 3], low: &str, high: &str) -> String {
    let mut s = String::from(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"420\" height=\"48\" viewBox=\"0 0 420 48\">\
         <defs><linearGradient id=\"heat\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">",
    );
    for i in 0..=10 {
        let t = i as f32 / 10.0;
        let [r, g, b] = colour(t);
        let _ = write!(s, "<stop offset=\"{t}\" stop-color=\"rgb({r},{g},{b})\"/>");
    }
    let _ = write!(
        s,
        "</linearGradient></defs><rect x=\"10\" y=\"4\" width=\"400\" height=\"20\" fill=\"url(#heat)\" stroke=\"#444\"/>\
         <text x=\"10\" y=\"42\" font-size=\"12\" font-family=\"sans-serif\">{}</text>\
         <text x=\"410\" y=\"42\" font-size=\"12\" font-family=\"sans-serif\" text-anchor=\"end\">{}</text></svg>",
        escape(low),
        escape(high)
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn page_escapes_text_and_embeds_pictures() {
        let p = page(
            "a <b>",
            &[
                Block::Text("x & y".into()),
                Block::Gallery(vec![Picture {
                    caption: "c\"".into(),
                    png: vec![1, 2, 3],
                }]),
                Block::Varies(vec![Block::Text("t".into())]),
            ],
        );
        assert!(p.contains("<h1>a &lt;b&gt;</h1>"));
        assert!(p.contains("<p>x &amp; y</p>"));
        assert!(p.contains("src=\"data:image/png;base64,AQID\""));
        assert!(p.contains("alt=\"c&quot;\""));
        assert!(p.contains("<!-- varies -->\n<p>t</p>\n<!-- /varies -->"));
        assert!(colour_bar(|_| [1, 2, 3], "0", "1").contains("rgb(1,2,3)"));
    }
}

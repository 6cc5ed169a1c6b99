//! Reads back an SVG written by the plots, for the tests of `plot` and `compare`.

/// `(data lines, texts)` of an SVG, which must parse with an `<svg>` root: a data line is
/// a `<polyline>` of more than two points (axes and ticks have two); the texts are every
/// `<text>` content, trimmed.
pub fn inspect_svg(svg: &[u8]) -> (usize, Vec<String>) {
    let text = std::str::from_utf8(svg).expect("SVG is UTF-8");
    let doc = roxmltree::Document::parse(text).expect("SVG is well-formed XML");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let lines = doc
        .descendants()
        .filter(|n| n.has_tag_name("polyline"))
        .filter(|n| {
            n.attribute("points")
                .unwrap_or("")
                .split_whitespace()
                .count()
                > 2
        })
        .count();
    let texts = doc
        .descendants()
        .filter(|n| n.has_tag_name("text"))
        .filter_map(|n| n.text().map(|t| t.trim().to_owned()))
        .collect();
    (lines, texts)
}

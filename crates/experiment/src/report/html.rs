//! The page skeleton of the report: escaping, the style sheet, the script (sortable tables,
//! the method / ground-truth wipe, and the page's self-check), image figures and the rows
//! table. Everything is inline: the page loads nothing from the network.
//!
//! The self-check runs on `load`: it counts the images that failed to decode (`naturalWidth`
//! 0), the plots without drawn marks and the script errors / `console.error` calls, and writes
//! them as `data-*` attributes of `#selfcheck` (`data-status="ok"` when all are zero), so a
//! headless browser's `--dump-dom` shows whether the page rendered.

/// HTML-escapes text.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = r#"
body{font-family:system-ui,sans-serif;margin:1.5em;color:#222;background:#fafafa}
h1{font-size:1.5em}h2{font-size:1.25em;border-bottom:1px solid #ccc;margin-top:2em}h3{font-size:1.05em}
.grid{display:flex;flex-wrap:wrap;gap:12px;align-items:flex-start}
figure{margin:0;background:#fff;border:1px solid #ddd;padding:6px;max-width:100%}
figure img{display:block;width:400px;max-width:100%;height:auto;image-rendering:pixelated}
figcaption{font-size:.8em;color:#555;max-width:400px;word-break:break-all}
.wipe{position:relative;display:inline-block}
.wipe img.top{position:absolute;left:0;top:0;clip-path:inset(0 calc(100% - var(--x,50%)) 0 0)}
.wipe input{width:100%}
table{border-collapse:collapse;font-size:.78em;background:#fff;margin:.5em 0}
th,td{border:1px solid #ddd;padding:2px 6px;text-align:right;white-space:nowrap}
th{cursor:pointer;background:#eee;position:sticky;top:0}th:hover{background:#ddd}
td.s{text-align:left}.scroll{overflow:auto;max-height:32em}
.meta{font-size:.85em;color:#555}code{font-size:.9em}
#selfcheck{font-size:.75em;color:#777;margin-top:3em}
"#;

const SCRIPT_HEAD: &str = r#"
window.__errors=[];
window.addEventListener('error',function(e){window.__errors.push(String(e.message||(e.target&&(e.target.src||e.target.href))||'error'))},true);
(function(){var ce=console.error;console.error=function(){window.__errors.push(Array.prototype.join.call(arguments,' '));ce.apply(console,arguments)}})();
"#;

const SCRIPT_BODY: &str = r#"
document.querySelectorAll('table.rows').forEach(function(t){
  t.querySelectorAll('th').forEach(function(th,col){
    th.addEventListener('click',function(){
      var body=t.tBodies[0],rows=Array.from(body.rows),asc=th.dataset.dir!=='asc';
      t.querySelectorAll('th').forEach(function(h){delete h.dataset.dir});th.dataset.dir=asc?'asc':'desc';
      rows.sort(function(a,b){
        var x=a.cells[col].dataset.v,y=b.cells[col].dataset.v,nx=parseFloat(x),ny=parseFloat(y),r;
        if(!isNaN(nx)&&!isNaN(ny)){r=nx-ny}else{r=String(x).localeCompare(String(y))}
        return asc?r:-r});
      rows.forEach(function(r){body.appendChild(r)});
    });
  });
});
document.querySelectorAll('.wipe input').forEach(function(s){
  s.addEventListener('input',function(){s.parentNode.style.setProperty('--x',s.value+'%')});
});
window.addEventListener('load',function(){
  var imgs=Array.from(document.images);
  var broken=imgs.filter(function(i){return !(i.complete&&i.naturalWidth>0)});
  var plots=Array.from(document.querySelectorAll('figure.plot svg'));
  var empty=plots.filter(function(s){return s.querySelectorAll('circle,path,polyline,line').length===0});
  var r=document.getElementById('selfcheck');
  r.dataset.images=imgs.length;r.dataset.broken=broken.length;
  r.dataset.plots=plots.length;r.dataset.emptyPlots=empty.length;
  r.dataset.errors=window.__errors.length;
  var ok=broken.length===0&&empty.length===0&&window.__errors.length===0;
  r.dataset.status=ok?'ok':'fail';
  r.textContent='self-check: '+(ok?'ok':'FAILED')+' ('+imgs.length+' images, '+broken.length+' broken; '+plots.length+' plots, '+empty.length+' empty; '+window.__errors.length+' script errors'+(window.__errors.length?': '+window.__errors.join(' | '):'')+')';
});
"#;

/// A whole page around `body`.
pub fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\
         <meta name=\"viewport\" content=\"width=device-width\"><style>{STYLE}</style>\
         <script>{SCRIPT_HEAD}</script></head><body><h1>{t}</h1>\n{body}\n\
         <div id=\"selfcheck\" data-status=\"pending\">self-check: pending</div>\
         <script>{SCRIPT_BODY}</script></body></html>\n",
        t = esc(title)
    )
}

/// A figure of one image.
pub fn figure(src: &str, caption: &str) -> String {
    format!(
        "<figure><img src=\"{}\" alt=\"{c}\"><figcaption>{c}</figcaption></figure>",
        esc(src),
        c = esc(caption)
    )
}

/// The wipe between a result (left of the slider) and its ground truth (right).
pub fn wipe(result: &str, truth: &str, caption: &str) -> String {
    format!(
        "<figure><div class=\"wipe\"><img src=\"{t}\" alt=\"ground truth\"><img class=\"top\" src=\"{r}\" alt=\"result\">\
         <input type=\"range\" min=\"0\" max=\"100\" value=\"50\" aria-label=\"wipe\"></div>\
         <figcaption>{c}: result left of the slider, ground truth (BVH) right</figcaption></figure>",
        t = esc(truth),
        r = esc(result),
        c = esc(caption)
    )
}

/// One table cell: a display text and a sort key.
pub struct Cell {
    pub text: String,
    pub sort: String,
    pub numeric: bool,
}

impl Cell {
    /// The cell of a JSON value: numbers with 4 significant digits, `-` for null.
    pub fn of(v: Option<&serde_json::Value>) -> Cell {
        use serde_json::Value;
        match v {
            None | Some(Value::Null) => Cell {
                text: "-".into(),
                sort: String::new(),
                numeric: false,
            },
            Some(Value::Number(n)) => {
                let f = n.as_f64().unwrap_or(f64::NAN);
                let text = if n.is_f64() {
                    let a = f.abs();
                    if a != 0.0 && !(1e-3..1e6).contains(&a) {
                        format!("{f:.3e}")
                    } else {
                        let d = (3 - a.log10().floor().max(0.0) as i32).max(0) as usize;
                        format!("{f:.d$}")
                    }
                } else {
                    n.to_string()
                };
                Cell {
                    text,
                    sort: n.to_string(),
                    numeric: true,
                }
            }
            Some(Value::String(s)) => Cell {
                text: s.clone(),
                sort: s.clone(),
                numeric: false,
            },
            // Nested rows (per-bounce lists, per-budget records) would fill the table with
            // JSON: the cell says how many entries there are and keeps the JSON as its tooltip.
            Some(other) => {
                let text = match other {
                    Value::Array(a) => format!("[{} entries]", a.len()),
                    Value::Object(o) => format!("{{{} fields}}", o.len()),
                    v => v.to_string(),
                };
                Cell {
                    text,
                    sort: other.to_string(),
                    numeric: false,
                }
            }
        }
    }
}

/// A sortable table.
pub fn table(columns: &[String], rows: &[Vec<Cell>]) -> String {
    let mut s = String::from("<div class=\"scroll\"><table class=\"rows\"><thead><tr>");
    for c in columns {
        s += &format!("<th>{}</th>", esc(c));
    }
    s += "</tr></thead><tbody>";
    for r in rows {
        s += "<tr>";
        for c in r {
            let title = if c.sort != c.text && !c.numeric {
                format!(" title=\"{}\"", esc(&c.sort))
            } else {
                String::new()
            };
            s += &format!(
                "<td{}{title} data-v=\"{}\">{}</td>",
                if c.numeric { "" } else { " class=\"s\"" },
                esc(&c.sort),
                esc(&c.text)
            );
        }
        s += "</tr>";
    }
    s + "</tbody></table></div>"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_cells_are_summarised_with_the_json_as_tooltip() {
        let v = serde_json::json!([{"bounce": 0}, {"bounce": 1}]);
        let c = Cell::of(Some(&v));
        assert_eq!(c.text, "[2 entries]");
        assert_eq!(c.sort, v.to_string());
        let html = table(&["bounces".into()], &[vec![c]]);
        assert!(html.contains(">[2 entries]</td>"), "{html}");
        assert!(html.contains("title=\"[{&quot;bounce&quot;:0}"), "{html}");
        let n = Cell::of(Some(&serde_json::json!(1.5)));
        assert!(!table(&["x".into()], &[vec![n]]).contains("title="));
    }
}

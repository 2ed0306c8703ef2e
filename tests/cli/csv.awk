# csvsplit(line, f): splits one CSV record as chatterlab writes it (RFC 4180 quoting, no line
# breaks inside fields) into f[1..n] and returns n. Plain awk (mawk) has no CSV mode.
function csvsplit(line, f,    n, i, c, field, quoted) {
  n = 0
  field = ""
  quoted = 0
  for (i = 1; i <= length(line); i++) {
    c = substr(line, i, 1)
    if (quoted) {
      if (c == "\"") {
        if (substr(line, i + 1, 1) == "\"") { field = field "\""; i++ }
        else quoted = 0
      } else field = field c
    } else if (c == "\"") quoted = 1
    else if (c == ",") { f[++n] = field; field = "" }
    else field = field c
  }
  f[++n] = field
  return n
}

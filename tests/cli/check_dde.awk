# Compares a linear_dde stability_map results.csv with reference/dde_rightmost_roots.csv.
# Usage: awk -v b_column=NAME|-v b=VALUE -v delay_column=NAME -f check_dde.awk (with csv.awk
# prepended) REFERENCE RESULTS. Prints one line per mismatch and exits 1 if there is any.
# Tolerance: 1e-9 relative (MODELS.md accuracy target for rightmost roots), i.e.
# |Re s - ref| <= 1e-9 |s_ref| and |f - f_ref| <= 1e-9 f_ref.
function abs(x) { return x < 0 ? -x : x }
BEGIN {
  split("growth_rate_per_s chatter_frequency_hz stable certified certified_real_part_per_s certificate status", names, " ")
  for (i in names) need[names[i]] = 1
  need[delay_column] = 1
  if (b_column != "") need[b_column] = 1
}
FNR == NR {
  if (FNR > 1) { csvsplit($0, r); key = sprintf("%.10g,%.10g", r[1], r[2]); g[key] = r[3]; f[key] = r[4] }
  next
}
FNR == 1 {
  n = csvsplit($0, h)
  for (i = 1; i <= n; i++) col[h[i]] = i
  for (name in need) if (!(name in col)) { print "missing column " name; bad++ }
  next
}
{
  csvsplit($0, v)
  bb = b_column != "" ? v[col[b_column]] : b
  key = sprintf("%.10g,%.10g", bb, v[col[delay_column]])
  rows++
  if (!(key in g)) { print "no reference for b,delay = " key; bad++; next }
  pi = atan2(0, -1)
  s_abs = sqrt(g[key] ^ 2 + (2 * pi * f[key]) ^ 2)
  growth = v[col["growth_rate_per_s"]]; freq = v[col["chatter_frequency_hz"]]
  if (growth == "" || abs(growth - g[key]) > 1e-9 * s_abs) {
    printf "b,delay = %s: growth_rate_per_s = %s, reference %s\n", key, growth, g[key]; bad++ }
  if (freq == "" || abs(freq - f[key]) > 1e-9 * f[key]) {
    printf "b,delay = %s: chatter_frequency_hz = %s, reference %s\n", key, freq, f[key]; bad++ }
  stable = (g[key] + 0 < 0) ? "true" : "false"
  if (v[col["stable"]] != stable) { printf "b,delay = %s: stable = %s\n", key, v[col["stable"]]; bad++ }
  if (v[col["certified"]] != "true") { printf "b,delay = %s: not certified: %s\n", key, v[col["certificate"]]; bad++ }
  cr = v[col["certified_real_part_per_s"]]
  if (cr == "" || cr + 0 < growth + 0) { printf "b,delay = %s: certified_real_part_per_s = %s below the root\n", key, cr; bad++ }
  if (v[col["status"]] != "ok") { printf "b,delay = %s: status %s\n", key, v[col["status"]]; bad++ }
}
END {
  if (rows != expected_rows) { printf "%d rows, expected %d\n", rows, expected_rows; bad++ }
  exit bad > 0
}

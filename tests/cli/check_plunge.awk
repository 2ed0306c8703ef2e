# Checks a plunge_regenerative stability_map results.csv: every reported root solves MODELS.md G1
# eq 2-16 and growth per wheel revolution is Tg Re s / 2 pi (G3). Independent of chatterlab's
# code: D(s) is written out here in plain complex arithmetic.
#   D(s) = 1 + kc [ sum_i (1/k_i)/(s^2/w_i^2 + 2 z_i s/w_i + 1)
#                   + 1/(kg (1 - e^{-Tg s})) + 1/(kw (1 - e^{-Tw s})) ]
# The residual is |D(s)| over 1 + kc * (sum of the terms' magnitudes), i.e. relative to the size
# of what cancels; a root found to Newton's 1e-13 gives ~1e-10 or less, a non-root O(1e-2..1).
# Usage (csv.awk prepended): awk -v kc= -v kg= -v kw= -v modes="f:z:k f:z:k" [-v wheel_rpm=]
#   [-v work_rpm=] -v expected_rows=N -f check_plunge.awk results.csv
function abs(x) { return x < 0 ? -x : x }
# Complex helpers: results in (cr, ci).
function cdiv(ar, ai, br, bi,    d) { d = br * br + bi * bi; cr = (ar * br + ai * bi) / d; ci = (ai * br - ar * bi) / d }
# 1/(k (1 - e^{-T s})) for s = x + i y
function regen(k, T, x, y,    m) { m = exp(-T * x); cdiv(1, 0, k * (1 - m * cos(T * y)), k * m * sin(T * y)) }
BEGIN { pi = atan2(0, -1); nm = split(modes, m, " ") }
FNR == 1 { n = csvsplit($0, h); for (i = 1; i <= n; i++) col[h[i]] = i; next }
{
  csvsplit($0, v)
  rows++
  ng = ("wheel_speed_rpm" in col) ? v[col["wheel_speed_rpm"]] : wheel_rpm
  nw = ("work_speed_rpm" in col) ? v[col["work_speed_rpm"]] : work_rpm
  x = v[col["growth_rate_per_s"]]; y = 2 * pi * v[col["chatter_frequency_hz"]]
  where = sprintf("row %d (wheel %s rpm, work %s rpm)", rows, ng, nw)
  if (v[col["status"]] != "ok" || x == "") { print where ": status " v[col["status"]]; bad++; next }
  sr = 0; si = 0; size = 0
  for (j = 1; j <= nm; j++) {
    split(m[j], p, ":"); w = 2 * pi * p[1]
    # s^2/w^2 + 2 z s/w + 1
    dr = (x * x - y * y) / (w * w) + 2 * p[2] * x / w + 1
    di = 2 * x * y / (w * w) + 2 * p[2] * y / w
    cdiv(1 / p[3], 0, dr, di); sr += cr; si += ci; size += sqrt(cr * cr + ci * ci)
  }
  regen(kg, 60 / ng, x, y); sr += cr; si += ci; size += sqrt(cr * cr + ci * ci)
  regen(kw, 60 / nw, x, y); sr += cr; si += ci; size += sqrt(cr * cr + ci * ci)
  residual = sqrt((1 + kc * sr) ^ 2 + (kc * si) ^ 2) / (1 + kc * size)
  if (!(residual <= 1e-8)) { printf "%s: |D(s)| relative %.3g at s = %s + %si\n", where, residual, x, y; bad++ }
  if (residual > worst) worst = residual
  rho = v[col["growth_rate_per_wheel_rev"]]; want = (60 / ng) * x / (2 * pi)
  if (rho == "" || abs(rho - want) > 1e-12 * abs(want)) { printf "%s: growth_rate_per_wheel_rev = %s, Tg Re s/2pi = %.17g\n", where, rho, want; bad++ }
  if (v[col["stable"]] != (x + 0 < 0 ? "true" : "false")) { print where ": stable = " v[col["stable"]]; bad++ }
  if (v[col["certified"]] != "true") { print where ": not certified: " v[col["certificate"]]; bad++ }
}
END {
  if (rows != expected_rows) { printf "%d rows, expected %d\n", rows, expected_rows; bad++ }
  printf "largest relative |D(s)|: %.3g\n", worst
  exit bad > 0
}

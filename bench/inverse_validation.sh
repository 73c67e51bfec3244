#!/usr/bin/env bash
# Validation of thorax inverse without inverse crime (issue 15, item 4), and the Utah tank as a
# real case. Prints the markdown tables of docs/validation.md ("The inverse problem").
#   phantom: the beat forward on the HIGH-resolution phantom (its own mesh and transfer), 30 dB
#            white noise added, inverted with the MEDIUM model's transfer matrix. The torso nodes
#            of the two models differ: the high-resolution forward samples its torso potential at
#            the medium torso's node positions (thorax forward --rows POSITIONS: each position
#            projected onto the high-resolution torso, the potential interpolated linearly on the
#            triangle it lands on). On the heart, each medium heart node is compared with the
#            nearest high-resolution heart node (thorax inverse --truth-model).
#   tank:    the Utah tank (tank_full_771 as outer, the closed 128-node sock as heart, meshed),
#            the transfer matrix sock -> the 192 tank leads, the measured tank leads of
#            cool1-atdr-run1.mat inverted, compared with the measured sock (channels 193-320).
# CC and RE per frame: median and 10th percentile of CC, median and 90th percentile of RE.
# Usage: bench/inverse_validation.sh [FRAMES]   (default 150 beat frames; the tank: all 608)
#        PARTS="phantom tank" (default both); WORK=DIR keeps and reuses the models and matrices
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
DATA=${DATA:-$PWD/../shared/data}
FRAMES=${1:-150}
W=${WORK:-$(mktemp -d)}
[ -n "${WORK:-}" ] || trap 'rm -rf "$W"' EXIT
mkdir -p "$W"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
PY=/usr/bin/python3
summary() { # DIR -> "cc_med cc_p10 re_med re_p90 lambda t_svd t_frames"
    $PY -c "import json,sys; j=json.load(open(sys.argv[1])); t=j['truth']; print('| %.3f | %.3f | %.3f | %.3f | %.3g | %.3f | %.3f |' % (t['cc_median'], t['cc_p10'], t['re_median'], t['re_p90'], j['lambda_used'], j['seconds_svd'], j['seconds_frames']))" "$1/inverse.json"
}
PARTS=${PARTS:-phantom tank}
if [[ " $PARTS " == *" phantom "* ]]; then
for res in medium high; do
    [ -d "$W/m_$res" ] && continue
    "$THORAX" phantom --resolution $res --seed 1 -o "$W/c_$res.txt" -q
    "$THORAX" surfaces "$W/c_$res.txt" -o "$W/m_$res" -q
    "$THORAX" mesh "$W/m_$res" --no-heart -q
    "$THORAX" beat "$W/m_$res" -o "$W/beat_$res.raw" --frames "$FRAMES" -q
done
outer=$($PY -c "import json,sys; m=json.load(open(sys.argv[1])); print([s['name'] for s in m['surfaces'] if s['role']=='outer'][0])" "$W/m_medium/model.json")
[ -d "$W/T_med" ] || "$THORAX" forward "$W/m_medium" --transfer-out -o "$W/T_med" -q
# the medium torso's node positions as electrodes on the high-resolution torso
awk '{print $1, $2, $3}' "$W/m_medium/$outer.pts" > "$W/medium_torso_positions.txt"
[ -d "$W/F_high" ] || "$THORAX" forward "$W/m_high" --epicardial "$W/beat_high.raw" --rows "$W/medium_torso_positions.txt" \
    --max-offset 30 -o "$W/F_high" -q
"$THORAX" series convert "$W/F_high/electrodes.raw" -o "$W/clean.mat" -q
$PY - "$W/clean.mat" "$W/noisy.mat" <<'PYEOF'
import sys, numpy as np, scipy.io as sio
b = sio.loadmat(sys.argv[1])['potvals']
rng = np.random.default_rng(15)
sigma = np.sqrt(np.mean(b ** 2)) * 10 ** (-30 / 20)   # 30 dB of the whole series' RMS
sio.savemat(sys.argv[2], {'potvals': b + rng.normal(0, sigma, b.shape), 'unit': 'mV'})
print("noise: sigma %.4g (30 dB of RMS %.4g); %d leads x %d frames" % (sigma, np.sqrt(np.mean(b ** 2)), *b.shape), file=sys.stderr)
PYEOF
T="$W/T_med/transfer.raw"
echo
echo "### Phantom: high-resolution forward, 30 dB noise, medium-resolution inverse ($FRAMES frames)"
echo
echo "| method | λ rule | λ per | CC median | CC 10th pct | RE median | RE 90th pct | λ used (median) | SVD s | frames s |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for method in tikhonov0 tikhonov1 tikhonov2 tsvd greensite tv; do
    for rule in lcurve creso gcv discrepancy; do
        [ "$method" = tsvd ] && [ "$rule" = creso ] && continue
        for per in frame series; do
            [ "$method" = tv ] && [ "$per" = series ] && continue
            extra=()
            [ "$rule" = discrepancy ] && extra=(--noise 30dB)
            [ "$method" = greensite ] && extra=(--noise 30dB)
            rm -rf "$W/inv"
            if "$THORAX" inverse --transfer "$T" --data "$W/noisy.mat" --method $method --lambda $rule --lambda-per $per \
                "${extra[@]}" --truth "$W/beat_high.raw" --truth-model "$W/m_high" -o "$W/inv" -q 2> "$W/err"; then
                echo "| $method | $rule | $per $(summary "$W/inv")"
            else
                echo "| $method | $rule | $per | failed: $(head -c 150 "$W/err") |"
            fi
        done
    done
done

fi
[[ " $PARTS " == *" tank "* ]] || exit 0
echo
echo "### Utah tank: measured tank leads inverted, compared with the measured sock"
echo
TANK=$DATA/map3d/geom/tank
REC=$DATA/map3d/data/tank/cool1-atdr-run1.mat
if [ ! -d "$W/tank" ]; then
    "$THORAX" import -o "$W/tank" "$TANK/tank_full_771.pts" --name tank --role outer \
        "$TANK/25feb97_sock_closed.pts" --name sock --role heart -q
    "$THORAX" mesh "$W/tank" -q
fi
[ -d "$W/T_tank" ] || "$THORAX" forward "$W/tank" --transfer-out --rows "$TANK/tank_leads_192.pts" -o "$W/T_tank" -q
{ echo "192 leads"; for i in $(seq 1 192); do echo " $i $i"; done; } > "$W/tank192.channels"
"$THORAX" series convert "$REC" --channels "$W/tank192.channels" -o "$W/tank_leads.raw" -q
"$THORAX" series convert "$REC" --channels "$TANK/sock128.channels" -o "$W/sock.raw" -q
"$THORAX" series convert "$W/sock.raw" -o "$W/sock.mat" -q
# CC and RE over all 608 frames (baseline included), and over the 150 frames of largest sock RMS
active() { # DIR -> "| CC median | RE median |" over the active frames
    $PY - "$1/lambda.txt" "$W/sock.mat" <<'PYEOF'
import sys, numpy as np, scipy.io as sio
rows = np.array([[float(v) for v in l.split()] for l in open(sys.argv[1]) if not l.startswith('#')])
s = sio.loadmat(sys.argv[2])['potvals']
idx = np.argsort(np.sqrt((s ** 2).mean(0)))[-150:]
print(' %.3f | %.3f |' % (np.median(rows[idx, 6]), np.median(rows[idx, 7])), end='')
PYEOF
}
echo "| method | λ rule | λ per | CC median | CC 10th pct | RE median | RE 90th pct | λ used (median) | SVD s | frames s | CC median, 150 active frames | RE median, active |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for method in tikhonov0 tikhonov1 tikhonov2 tsvd greensite tv; do
    for rule in lcurve creso gcv; do
        [ "$method" = tsvd ] && [ "$rule" = creso ] && continue
        for per in frame series; do
            [ "$method" = tv ] && [ "$per" = series ] && continue
            rm -rf "$W/inv"
            if "$THORAX" inverse --transfer "$W/T_tank/transfer_electrodes.raw" --data "$W/tank_leads.raw" --method $method \
                --lambda $rule --lambda-per $per --truth "$W/sock.raw" -o "$W/inv" -q 2> "$W/err"; then
                echo "| $method | $rule | $per $(summary "$W/inv") $(active "$W/inv")"
            else
                echo "| $method | $rule | $per | failed: $(head -c 150 "$W/err") |"
            fi
        done
    done
done

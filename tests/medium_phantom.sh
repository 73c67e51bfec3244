# Sourced by the end-to-end tests that start from the medium phantom (seed 1) meshed without the
# heart, in the current directory: c.txt and model/. Under the sanitizers (THORAX_QUICK) the same
# files are copied from the fixture tests/phantom_models.sh made once (CMakeLists.txt).
medium_phantom() {
    if [ -n "${THORAX_QUICK:-}" ] && [ -d "${THORAX_PHANTOM_MODELS:-}" ]; then
        cp -r "$THORAX_PHANTOM_MODELS/c.txt" "$THORAX_PHANTOM_MODELS/model" .
    else
        "$THORAX" phantom --resolution medium --seed 1 -o c.txt -q &&
            "$THORAX" surfaces c.txt -o model -q &&
            "$THORAX" mesh model --no-heart -q
    fi
}

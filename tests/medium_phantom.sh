# Sourced by the end-to-end tests that start from the medium phantom (seed 1) meshed without the
# heart, in the current directory: c.txt and model/. Under ctest (THORAX_PHANTOM_MODELS, every build)
# the same files are copied from the fixture tests/phantom_models.sh made once (CMakeLists.txt);
# run alone, without it, the test makes them itself with the same commands.
medium_phantom() {
    if [ -d "${THORAX_PHANTOM_MODELS:-}" ]; then
        cp -r "$THORAX_PHANTOM_MODELS/c.txt" "$THORAX_PHANTOM_MODELS/model" .
    else
        "$THORAX" phantom --resolution medium --seed 1 -o c.txt -q &&
            "$THORAX" surfaces c.txt -o model -q &&
            "$THORAX" mesh model --no-heart -q
    fi
}

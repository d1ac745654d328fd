#!/bin/sh
# Re-render the bundled sample clip and its exact ground truth (deterministic: seeded).
# The procedural walk has the model's proportions (body.LENGTH); no third-party data.
set -e
cd "$(dirname "$0")"
mocap synth walk-cycle walk.mp4 --view three-quarter --seconds 3.3 --seed 1

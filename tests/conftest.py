"""Shared test set-up: rendering runs headless; optimal energies are cached in a temporary directory."""

import os
import tempfile

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
# The tests never read or write the user's cache of optimal energies (~/.cache/dwr-gym).
os.environ.setdefault("DWR_GYM_CACHE", tempfile.mkdtemp(prefix="dwr-gym-test-cache-"))

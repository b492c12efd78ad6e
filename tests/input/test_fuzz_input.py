"""Mutated OSC packets, serial lines and recordings end in events or counted bad messages
(a ReplayError for a recording): short fixed-seed runs of tools/fuzz.py's input targets."""

from __future__ import annotations

import pytest

from tools.fuzz_input import OSC, RECORDING, SERIAL


# OSC mutations rarely stay valid (about 1 in 300): 1,500 inputs reach several that do
# (600 reached two, and on a loaded machine sometimes none).
@pytest.mark.parametrize(("target", "inputs"), [(OSC, 1500), (SERIAL, 250), (RECORDING, 250)],
                         ids=["osc", "serial", "recording"])
def test_fuzzed_input_streams_are_events_or_messages(target, inputs, fuzz_briefly):
    fuzz_briefly(target, inputs)

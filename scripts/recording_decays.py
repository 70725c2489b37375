#!/usr/bin/python3
"""Independent check of `chladni estimate`'s partials on the bundled recordings: each partial is
isolated by a zero-phase band-pass (4th-order Butterworth, +-2.5 % around it), its Hilbert
envelope is fitted by a straight line in dB from the peak until it falls 30 dB, comes within
6 dB of the noise, or the file ends, and the slope gives the decay rate d (1/s). Needs python3-numpy and python3-scipy
(/usr/bin/python3 on Debian). Usage: scripts/recording_decays.py [recordings/]"""
import sys
import numpy as np
import scipy.io.wavfile as wavfile
import scipy.signal as sg

PARTIALS = {  # Hz, from a 1 M-point FFT peak search of each file (docs/validation.md)
    "glockenspiel_C6": (0.798, [1049.77, 2877.53, 5553.96, 7225.91, 11016.02, 13339.20]),
    "marimba_C4": (None, [261.58, 1046.33]),
    "xylophone_C5": (None, [523.18, 1566.59, 3033.57]),
    "woodblock_C4": (None, [1636.88]),
}

def decay(x, fs, f):
    sos = sg.butter(4, [f * 0.975, f * 1.025], btype="band", fs=fs, output="sos")
    env = np.abs(sg.hilbert(sg.sosfiltfilt(sos, x)))
    db = 20 * np.log10(env + 1e-12)
    p = int(np.argmax(db[: int(0.2 * fs)]))
    low = db[p:].min()  # the noise, or the end of a partial that still rings
    if low < db[p] - 36:
        limit = db[p] - 30
    elif low < db[p] - 20:
        limit = low + 6
    else:
        limit = -np.inf  # rings to the end of the file
    stop = p + 1
    while stop < len(db) and db[stop] > limit:
        stop += 1
    t = np.arange(p, stop) / fs
    slope = np.polyfit(t, db[p:stop], 1)[0]
    return -slope / (20 / np.log(10)), (stop - p) / fs

folder = sys.argv[1] if len(sys.argv) > 1 else "recordings"
for name, (end, partials) in PARTIALS.items():
    fs, x = wavfile.read(f"{folder}/{name}.wav")
    x = x.astype(float)
    if x.ndim > 1:
        x = x.mean(axis=1)
    if end:
        x = x[: int(end * fs)]
    for f in partials:
        d, span = decay(x, fs, f)
        print(f"{name:16s} {f:9.2f} Hz  d = {d:7.3f} 1/s over {span:.3f} s")

#!/usr/bin/env python3
# Peak level per frequency band of a WAV segment, relative to the loudest (docs/transfer.md).
# Usage: /usr/bin/python3 scripts/partials.py FILE.wav T0 T1   (needs python3-numpy, -scipy)
import sys
import warnings

import numpy as np
from scipy.io import wavfile

warnings.simplefilter('ignore')
sr, x = wavfile.read(sys.argv[1])
x = x.astype(np.float64)
if x.ndim > 1: x = x.mean(axis=1)
t0, t1 = float(sys.argv[2]), float(sys.argv[3])
seg = x[int(t0*sr):int(t1*sr)]
w = np.hanning(len(seg)); X = np.abs(np.fft.rfft(seg*w)); f = np.fft.rfftfreq(len(seg), 1/sr)
db = 20*np.log10(X/X.max()+1e-30)
for lo, hi in [(400,480),(1100,1180),(2000,2100),(3100,3250),(4400,4500),(5700,6000),(6300,6900),(7300,7600),(8000,8400),(9000,20000)]:
    m = (f>=lo)&(f<hi); i = np.argmax(X[m]); print(f"{lo:5d}-{hi:5d} Hz: peak {f[m][i]:8.1f} Hz {db[m][i]:7.1f} dB")

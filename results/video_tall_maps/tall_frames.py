"""Render the tall map's episode (tall.pkl) at stride 40 into OUT.npz."""
import pickle, sys
import numpy as np
from rrtdrive.sim.video import render_frames
ep = pickle.load(open("tall.pkl", "rb"))
np.savez_compressed(sys.argv[1], *list(render_frames(ep, stride=40)))

"""Hash every frame (stride 1) of each pickled episode: python dump.py OUT.json."""
import glob, hashlib, json, os, pickle, sys, time
import rrtdrive
from rrtdrive.sim.video import render_frames
out = {}
t = time.time()
for f in sorted(glob.glob("eps/*.pkl")):
    ep = pickle.load(open(f, "rb"))
    if len(ep.log.states) == 0: continue
    hs, shape = [], None
    for fr in render_frames(ep, stride=1):
        hs.append(hashlib.sha1(fr.tobytes()).hexdigest()); shape = fr.shape
    out[os.path.basename(f)[:-4]] = {"shape": shape, "hashes": hs}
json.dump(out, open(sys.argv[1], "w"))
print(rrtdrive.__file__, len(out), sum(len(v["hashes"]) for v in out.values()), f"{time.time()-t:.1f}s")

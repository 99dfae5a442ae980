"""Compare two dump.py outputs frame by frame: python compare.py old.json new.json."""
import json
import sys

a, b = (json.load(open(p)) for p in sys.argv[1:3])
same = 0
for k in a:
    ok = a[k]["hashes"] == b[k]["hashes"] and a[k]["shape"] == b[k]["shape"]
    same += ok
    print(f"{k:28s} {a[k]['shape']} -> {b[k]['shape']}  {len(a[k]['hashes']):5d} frames  "
          f"{'identical' if ok else 'DIFFERENT'}")
print(f"{same}/{len(a)} episodes identical, "
      f"{sum(len(v['hashes']) for v in a.values())} frames compared (sha1 of the RGB arrays)")

"""Random damage to small mesh files, each through `seamvox info` and then `seamvox param`: any
exit code other than 0, 1 or 2, or a run over 60 s, is printed as BAD. Usage (in an empty folder):
  python3 bench/broken/mutations.py SEED COUNT      (SEAMVOX: the binary, default build/seamvox)
It writes a 3,000-face generated scan as binary and ASCII PLY, OBJ, OFF and Draco first."""
import os
import random
import subprocess
import sys

random.seed(int(sys.argv[1]) if len(sys.argv) > 1 else 1)
svx = os.environ.get('SEAMVOX', os.path.join(os.path.dirname(os.path.abspath(__file__)), '../../build/seamvox'))
subprocess.run([svx, 'gen', 'scan', '--faces', '3000', '-o', 'small.ply', '--quiet'], check=True, capture_output=True)
srcs = ['small.ply', 'small_ascii.ply', 'small.obj', 'small.off', 'small.drc']
subprocess.run([svx, 'convert', 'small.ply', 'small_ascii.ply', '--ascii', '--quiet'], check=True, capture_output=True)
for other in srcs[2:]:
    subprocess.run([svx, 'convert', 'small.ply', other, '--quiet'], check=True, capture_output=True)
bad = []
for i in range(int(sys.argv[2]) if len(sys.argv) > 2 else 150):
    src = random.choice(srcs)
    data = bytearray(open(src, 'rb').read())
    kind = random.choice(['flip', 'trunc', 'digits', 'dup'])
    if kind == 'flip':
        for _ in range(random.randint(1, 8)):
            data[random.randrange(len(data))] = random.randrange(256)
    elif kind == 'trunc':
        data = data[:random.randrange(len(data))]
    elif kind == 'digits':
        # a digit in the first 400 bytes (the header) replaced by a large, negative or odd number
        head = min(len(data), 400)
        pos = [j for j in range(head) if chr(data[j]).isdigit()]
        if pos:
            j = random.choice(pos)
            data[j:j+1] = random.choice([b'99999999', b'-1', b'0', b'4294967295', b'1e30'])
        else:
            j = random.randrange(len(data)); data[j:j] = random.choice([b'-1', b'nan', b'1e400'])
    else:
        a = random.randrange(len(data)); b = min(len(data), a + random.randrange(1, 200))
        data[a:a] = data[a:b]
    ext = os.path.splitext(src)[1]
    path = f'm{i}{ext}'
    open(path, 'wb').write(data)
    for cmd in (['info', path], ['param', path, '-o', f'o{i}.ply']):
        try:
            p = subprocess.run([svx] + cmd, capture_output=True, timeout=60)
            rc = p.returncode
            err = p.stderr.decode(errors='replace').strip().splitlines()[-1:] if p.stderr else []
        except subprocess.TimeoutExpired:
            rc, err = 'timeout', []
        if rc not in (0, 1, 2):
            bad.append((path, kind, cmd[0], rc, err))
            print('BAD', path, kind, cmd[0], rc, err, flush=True)
            break
        if cmd[0] == 'info' and rc != 0:
            break
    if not any(b[0] == path for b in bad):
        os.remove(path)
    if os.path.exists(f'o{i}.ply'): os.remove(f'o{i}.ply')
print('done', len(bad))

"""Moiré in a patch of rendered PNGs (issue 42, item 6d; docs/performance.md).

Standard library only: `python3 scripts/bench/bench-moire.py X0,Y0,X1,Y1 REF.png A.png
[B.png ...]` prints, over the pixels x0..x1, y0..y1 of each image (grey = the mean of
R, G, B, 0-255): its mean, the RMS difference against REF (a render at a fine step) and
the RMS of its discrete Laplacian (the energy at the highest spatial frequencies, where
moiré and sampling noise sit). 8-bit RGB or RGBA PNGs, as `glint render` writes them.
"""
import sys, zlib, struct
def read(p):
    d = open(p, 'rb').read(); pos = 8; idat = b''; w = h = 0
    while pos < len(d):
        n, t = struct.unpack('>I4s', d[pos:pos+8]); c = d[pos+8:pos+8+n]; pos += 12 + n
        if t == b'IHDR': w, h, depth, ctype = struct.unpack('>IIBB', c[:10]); ch = {2:3, 6:4, 0:1}[ctype]
        elif t == b'IDAT': idat += c
    raw = zlib.decompress(idat); stride = w*ch; rows = []; prev = bytearray(stride); i = 0
    for y in range(h):
        f = raw[i]; line = bytearray(raw[i+1:i+1+stride]); i += 1+stride
        for x in range(stride):
            a = line[x-ch] if x >= ch else 0; b = prev[x]; cc = prev[x-ch] if x >= ch else 0
            if f == 1: line[x] = (line[x]+a) & 255
            elif f == 2: line[x] = (line[x]+b) & 255
            elif f == 3: line[x] = (line[x]+(a+b)//2) & 255
            elif f == 4:
                pp = a+b-cc; pa, pb, pc = abs(pp-a), abs(pp-b), abs(pp-cc)
                line[x] = (line[x]+(a if pa <= pb and pa <= pc else b if pb <= pc else cc)) & 255
        rows.append([sum(line[x*ch:x*ch+3])/3 for x in range(w)]); prev = line
    return rows
x0, y0, x1, y1 = map(int, sys.argv[1].split(','))
ref = read(sys.argv[2])
for p in sys.argv[3:]:
    im = read(p)
    pts = [(x, y) for y in range(y0, y1) for x in range(x0, x1)]
    rms = (sum((im[y][x]-ref[y][x])**2 for x, y in pts)/len(pts))**0.5
    mean = sum(im[y][x] for x, y in pts)/len(pts)
    # high frequencies: the Laplacian's RMS
    lap = (sum((4*im[y][x]-im[y-1][x]-im[y+1][x]-im[y][x-1]-im[y][x+1])**2 for x, y in pts)/len(pts))**0.5
    print(f"{p}: mean {mean:.1f}, RMS vs reference {rms:.2f}, Laplacian RMS {lap:.2f}")

#!/usr/bin/env python3
"""VTK's side of scripts/bench/bench-vtk-surface: surface rendering and isosurface extraction.

Modes:
  render SCENE.json FRAMES OUT.png|- [MESH.ply ...]
      Renders the scene glint dumped (glint render MESH... --dump-scene SCENE.json):
      its meshes from the PLY files given, one per mesh in order (glint mesh X.gii -o
      X.ply converts them with glint's vertex normals), and, when the scene is in
      surface mode with a volume, the vtkFlyingEdges3D isosurface of that volume at the
      scene's iso value (normals from the gradient, as glint's). Same camera, image
      size, material and shininess, headlight; per-pixel (Phong) lighting; no
      multisampling. Offscreen
      through EGL with the PyPI wheel, so on a machine without a GPU this is Mesa's
      software rasterizer, llvmpipe. Prints ms per frame after one warm-up frame.
  extract VOLUME ISO FRAMES
      vtkFlyingEdges3D on the NIfTI volume in memory (normals on, as glint's), ms per
      extraction, the reader outside the timing.
  e2e VOLUME ISO OUT.stl
      What a user's script does: read the NIfTI, extract, write a binary STL. Prints
      the time of the three steps (the interpreter's start and `import vtk` excluded).
"""

import json
import statistics
import sys
import time

import vtk


def nifti_image(path):
    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    # Place the grid with the sform's translation (exact for the MNI152 template's
    # axis-aligned, positive-diagonal affine; checked).
    m = reader.GetSFormMatrix() or reader.GetQFormMatrix()
    if m is not None:
        for r in range(3):
            for c in range(3):
                if r != c and abs(m.GetElement(r, c)) > 1e-6:
                    sys.exit("bench-vtk-surface.py: only axis-aligned affines are supported")
            if m.GetElement(r, r) <= 0:
                sys.exit("bench-vtk-surface.py: only positive-diagonal affines are supported")
        image.SetOrigin(m.GetElement(0, 3), m.GetElement(1, 3), m.GetElement(2, 3))
    return image


def flying_edges(image, iso):
    fe = vtk.vtkFlyingEdges3D()
    fe.SetInputData(image)
    fe.SetValue(0, iso)
    fe.ComputeNormalsOn()
    fe.ComputeGradientsOff()
    fe.ComputeScalarsOff()
    return fe


def render(scene_path, frames, out_png, plys):
    with open(scene_path) as f:
        scene = json.load(f)
    ren = vtk.vtkRenderer()
    ren.SetBackground(*scene["background"])
    triangles = 0
    sources = []
    colors = []
    for mesh, ply in zip(scene.get("meshes", []), plys):
        reader = vtk.vtkPLYReader()
        reader.SetFileName(ply)
        reader.Update()
        sources.append(reader.GetOutput())
        colors.append(mesh["color"])
    if len(sources) != len(scene.get("meshes", [])):
        sys.exit("bench-vtk-surface.py: give one PLY per mesh of the scene")
    if scene.get("mode") == "surface" and isinstance(scene.get("input"), dict):
        fe = flying_edges(nifti_image(scene["input"]["path"]), scene["iso"])
        fe.Update()
        sources.append(fe.GetOutput())
        colors.append(SURFACE_COLOR)
    material = scene["material"]
    for poly, color in zip(sources, colors):
        triangles += poly.GetNumberOfCells()
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputData(poly)
        mapper.ScalarVisibilityOff()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.SetColor(*color)
        prop.SetAmbient(material["ambient"])
        prop.SetDiffuse(material["diffuse"])
        prop.SetSpecular(material["specular"])
        prop.SetSpecularPower(scene["lobe"]["n"])
        prop.SetInterpolationToPhong()
        ren.AddActor(actor)
    derived = scene["derived"]
    cam = ren.GetActiveCamera()
    cam.SetPosition(*derived["eye"])
    cam.SetFocalPoint(*derived["focal_point"])
    cam.SetViewUp(*derived["view_up"])
    if scene["camera"]["projection"] == "perspective":
        cam.SetViewAngle(derived["view_angle_deg"])
    else:
        cam.ParallelProjectionOn()
        cam.SetParallelScale(derived["parallel_scale"])
    ren.ResetCameraClippingRange()
    ren.TwoSidedLightingOn()  # glint's headlight lights both sides as well

    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.SetMultiSamples(0)
    win.AddRenderer(ren)
    win.SetSize(*scene["size"])
    win.Render()  # warm-up: shader compilation, buffer upload
    times = []
    for _ in range(frames):
        start = time.perf_counter()
        win.Render()
        times.append((time.perf_counter() - start) * 1e3)
    ms = sum(times) / frames
    caps = win.ReportCapabilities().splitlines()
    gl = next((l.split(":", 1)[1].strip() for l in caps if "OpenGL renderer" in l), "?")
    print(f"vtk: {ms:.2f} ms/frame ({frames} frames, {scene['size'][0]}x{scene['size'][1]}, "
          f"{triangles} triangles, {gl}, VTK {vtk.vtkVersion.GetVTKVersion()}; "
          f"median {statistics.median(times):.2f} ms)")
    if out_png:
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(win)
        grab.Update()
        writer = vtk.vtkPNGWriter()
        writer.SetFileName(out_png)
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()


# glint_render::SURFACE_COLOR, the isosurface's colour.
SURFACE_COLOR = (0.85, 0.77, 0.64)


def extract(volume, iso, frames):
    image = nifti_image(volume)
    fe = flying_edges(image, iso)
    fe.Update()  # warm-up
    start = time.perf_counter()
    for _ in range(frames):
        fe.Modified()
        fe.Update()
    ms = (time.perf_counter() - start) * 1e3 / frames
    print(f"vtk: {ms:.2f} ms/extraction ({frames} runs, {fe.GetOutput().GetNumberOfCells()} "
          f"triangles, vtkFlyingEdges3D, VTK {vtk.vtkVersion.GetVTKVersion()})")


def e2e(volume, iso, out_stl):
    start = time.perf_counter()
    fe = flying_edges(nifti_image(volume), iso)
    writer = vtk.vtkSTLWriter()
    writer.SetFileTypeToBinary()
    writer.SetFileName(out_stl)
    writer.SetInputConnection(fe.GetOutputPort())
    writer.Write()
    ms = (time.perf_counter() - start) * 1e3
    print(f"vtk: {ms:.2f} ms end to end (read, vtkFlyingEdges3D, binary STL)")


def main():
    mode = sys.argv[1] if len(sys.argv) > 1 else ""
    if mode == "render":
        out = sys.argv[4] if len(sys.argv) > 4 and sys.argv[4] != "-" else None
        render(sys.argv[2], int(sys.argv[3]), out, sys.argv[5:])
    elif mode == "extract":
        extract(sys.argv[2], float(sys.argv[3]), int(sys.argv[4]))
    elif mode == "e2e":
        e2e(sys.argv[2], float(sys.argv[3]), sys.argv[4])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()

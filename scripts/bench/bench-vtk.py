#!/usr/bin/env python3
"""Render the scene glint dumped (--dump-scene) with VTK's CPU ray caster,
vtkFixedPointVolumeRayCastMapper, and print ms per frame.

Used by scripts/bench/bench-vtk; run it through that script. The scene JSON is glint's
resolved scene (schema version 1): the volume path, image size, projection and
material from the scene itself, and from its "derived" block the camera (eye, focal
point, view up, view angle), the transfer function points (already scaled the way
glint uses them) and the sample distance in mm. VTK gets: AutoAdjustSampleDistances off, SampleDistance = step in
world mm (VTK's unit), ImageSampleDistance 1, linear interpolation, shading on,
ScalarOpacityUnitDistance = the smallest spacing (glint's opacity unit is one voxel),
the renderer's default headlight, offscreen rendering (EGL with the PyPI wheel).

Usage: bench-vtk.py SCENE.json FRAMES [OUT.png]

FRAMES 0 is the end-to-end mode: read the file, render the first frame, write the PNG
and exit, printing "vtk-e2e: MS ms", the time from the start of main() (after the
interpreter started and `import vtk`, which issue 31 excludes) to the PNG written.
"""

import json
import os
import sys
import time

import vtk


def main():
    t0 = time.perf_counter()
    scene_path, frames = sys.argv[1], int(sys.argv[2])
    out_png = sys.argv[3] if len(sys.argv) > 3 else None
    with open(scene_path) as f:
        scene = json.load(f)
    if scene.get("version") != 1:
        sys.exit(f"bench-vtk.py: scene version {scene.get('version')} is not supported (1 is)")
    derived = scene["derived"]
    tf = derived["transfer_function"]
    material = scene["material"]

    reader = vtk.vtkNIFTIImageReader()
    reader.SetFileName(scene["input"]["path"])
    reader.Update()
    image = reader.GetOutput()
    # glint works in RAS+ world mm through the NIfTI sform. VTK's reader gives the
    # grid in index order with spacing and no orientation; place it with the sform's
    # translation. This is exact for axis-aligned, positive-diagonal affines (the
    # MNI152 template's), which is checked here.
    m = reader.GetSFormMatrix() or reader.GetQFormMatrix()
    if m is not None:
        for r in range(3):
            for c in range(3):
                if r != c and abs(m.GetElement(r, c)) > 1e-6:
                    sys.exit("bench-vtk.py: only axis-aligned affines are supported")
            if m.GetElement(r, r) <= 0:
                sys.exit("bench-vtk.py: only positive-diagonal affines are supported")
        image.SetOrigin(m.GetElement(0, 3), m.GetElement(1, 3), m.GetElement(2, 3))

    ctf = vtk.vtkColorTransferFunction()
    for x, r, g, b in tf["color"]:
        ctf.AddRGBPoint(x, r, g, b)
    otf = vtk.vtkPiecewiseFunction()
    for x, a in tf["opacity"]:
        otf.AddPoint(x, a)

    prop = vtk.vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetInterpolationTypeToLinear()
    prop.SetScalarOpacityUnitDistance(derived["min_spacing_mm"])
    if material["shade"]:
        prop.ShadeOn()
    prop.SetAmbient(material["ambient"])
    prop.SetDiffuse(material["diffuse"])
    prop.SetSpecular(material["specular"])
    prop.SetSpecularPower(scene["lobe"]["n"])

    # GLINT_VTK_MAPPER=gpu: VTK's GPU ray caster (on Mesa llvmpipe without a GPU);
    # GLINT_VTK_SCATTERING=B: its volumetric scattering model (shadows and a
    # Henyey-Greenstein phase function) with blending B, vtkGPUVolumeRayCastMapper
    # ::SetVolumetricScatteringBlending (VTK 9.2+), anisotropy 0.
    scattering = os.environ.get("GLINT_VTK_SCATTERING")
    if os.environ.get("GLINT_VTK_MAPPER") == "gpu" or scattering is not None:
        mapper = vtk.vtkGPUVolumeRayCastMapper()
        if scattering is not None:
            mapper.SetVolumetricScatteringBlending(float(scattering))
            mapper.SetGlobalIlluminationReach(1.0)
            prop.SetScatteringAnisotropy(0.0)
    else:
        mapper = vtk.vtkFixedPointVolumeRayCastMapper()
    mapper.SetInputConnection(reader.GetOutputPort())
    mapper.SetInputData(image)
    mapper.AutoAdjustSampleDistancesOff()
    mapper.SetSampleDistance(derived["step_mm"])
    mapper.SetImageSampleDistance(1.0)

    volume = vtk.vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)

    ren = vtk.vtkRenderer()
    ren.SetBackground(0, 0, 0)
    ren.AddVolume(volume)
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

    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(*scene["size"])

    # First frame: the mapper builds its gradient tables and min/max volume (glint's
    # equivalent, building the Field, is outside its timed loop too).
    win.Render()
    if frames > 0:
        report(win, mapper, scene, frames)
    if out_png:
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(win)
        grab.Update()
        writer = vtk.vtkPNGWriter()
        writer.SetFileName(out_png)
        writer.SetInputConnection(grab.GetOutputPort())
        writer.Write()
    if frames == 0:
        print(f"vtk-e2e: {(time.perf_counter() - t0) * 1e3:.1f} ms")


def report(win, mapper, scene, frames):
    """Times FRAMES more frames and prints ms per frame."""
    start = time.perf_counter()
    for _ in range(frames):
        win.Render()
    ms = (time.perf_counter() - start) * 1e3 / frames
    print(f"vtk: {ms:.2f} ms/frame ({frames} frames, {scene['size'][0]}x{scene['size'][1]}, "
          f"{mapper.GetClassName()}, VTK "
          f"{vtk.vtkVersion.GetVTKVersion()})")


if __name__ == "__main__":
    main()

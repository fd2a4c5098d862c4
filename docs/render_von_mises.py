# Renders a bigstep frame coloured by von Mises stress with ParaView
# (Debian's pvpython; under xvfb-run on a machine without a display):
#   xvfb-run -a pvpython docs/render_von_mises.py FRAME.vtu OUT.png [WARP]
# WARP scales the displacement for the picture (1: true shape).
import sys
from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction, GetScalarBar,
                             OpenDataFile, Render, ResetCamera, SaveScreenshot, Show, WarpByVector)

frame, out = sys.argv[1], sys.argv[2]
warp = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
src = OpenDataFile(frame)
rest = WarpByVector(Input=src, Vectors=["POINTS", "displacement"], ScaleFactor=-1.0)
shape = WarpByVector(Input=rest, Vectors=["POINTS", "displacement"], ScaleFactor=warp)
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1200, 500]
view.UseColorPaletteForBackground = 0
view.Background = [1, 1, 1]
view.OrientationAxesVisibility = 0
d = Show(shape, view)
d.Representation = "Surface"
ColorBy(d, ("CELLS", "von_mises"))
lut = GetColorTransferFunction("von_mises")
lut.ApplyPreset("Viridis (matplotlib)", True)
d.SetScalarBarVisibility(view, True)
bar = GetScalarBar(lut, view)
bar.Title = "von Mises stress (Pa)"
bar.ComponentTitle = ""
bar.TitleColor = bar.LabelColor = [0, 0, 0]
view.CameraPosition = [0.5, 0.3, 2.2]
view.CameraFocalPoint = [0.5, 0.0, 0.05]
view.CameraViewUp = [0, 1, 0]
ResetCamera()
view.GetActiveCamera().Zoom(2.0)
Render()
SaveScreenshot(out, view, ImageResolution=[1200, 500])

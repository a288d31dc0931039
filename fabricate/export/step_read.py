"""Read a STEP assembly back with OpenCASCADE: ``[(name, solid shape), ...]`` in file order."""
from __future__ import annotations

from pathlib import Path

from optimize.errors import ExportError


def read_step(path) -> tuple[list[tuple[str, object]], dict]:
    """Named solids of a STEP file (XCAF: component names, else product names) and facts.

    Facts: ``roots`` (free shapes), ``colours`` ``{name: (r, g, b)}`` sRGB 0..1 of
    each solid's surface colour (absent when the file has none).
    Raises ExportError when OpenCASCADE cannot read the file.
    """
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.Message import Message, Message_Gravity
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.collections import Sequence_TDF_Label as TDF_LabelSequence
    from OCP.TDF import TDF_Label
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFApp import XCAFApp_Application
    from OCP.Quantity import Quantity_Color, Quantity_TOC_sRGB
    from OCP.XCAFDoc import XCAFDoc_ColorType, XCAFDoc_DocumentTool, XCAFDoc_ShapeTool

    for printer in Message.DefaultMessenger_s().Printers():
        printer.SetTraceLevel(Message_Gravity.Message_Fail)
    path = Path(path)
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    XCAFApp_Application.GetApplication_s().NewDocument(TCollection_ExtendedString("MDTV-XCAF"), doc)
    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    reader.SetColorMode(True)
    if reader.ReadFile(str(path)) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise ExportError(f"{path}: OpenCASCADE cannot read the STEP file")
    if not reader.Transfer(doc):
        raise ExportError(f"{path}: OpenCASCADE cannot transfer the STEP file")
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    colour_tool = XCAFDoc_DocumentTool.ColorTool_s(doc.Main())
    colours = {}

    def colour_of(name, shape) -> None:
        c = Quantity_Color()
        if colour_tool.GetColor(shape, XCAFDoc_ColorType.XCAFDoc_ColorSurf, c):
            colours[name] = tuple(round(x, 6) for x in c.Values(Quantity_TOC_sRGB))

    def name_of(label) -> str:
        attr = TDataStd_Name()
        if label.FindAttribute(TDataStd_Name.GetID_s(), attr):
            return attr.Get().ToExtString()
        return ""

    roots = TDF_LabelSequence()
    tool.GetFreeShapes(roots)
    out = []
    for r in range(1, roots.Length() + 1):
        root = roots.Value(r)
        if not XCAFDoc_ShapeTool.IsAssembly_s(root):
            out.append((name_of(root), XCAFDoc_ShapeTool.GetShape_s(root)))
            continue
        comps = TDF_LabelSequence()
        XCAFDoc_ShapeTool.GetComponents_s(root, comps, False)
        for c in range(1, comps.Length() + 1):
            comp = comps.Value(c)
            ref = TDF_Label()
            XCAFDoc_ShapeTool.GetReferredShape_s(comp, ref)
            name = name_of(ref) or name_of(comp)
            out.append((name, XCAFDoc_ShapeTool.GetShape_s(comp)))
            colour_of(name, XCAFDoc_ShapeTool.GetShape_s(ref))
    return out, {"roots": roots.Length(), "colours": colours}


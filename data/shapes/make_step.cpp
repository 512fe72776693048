// Writes the STEP fixtures of issue #14 (docs/nurbs-step-design.md §6) with OpenCASCADE:
//   sphere.step        the sphere r = 1 centred at the origin
//   torus.step         the torus R = 1, r = 0.3 about z, centred at the origin
//   filleted_box.step  the box [-1, 1]³ with every one of its 12 edges filleted, r = 0.3
//   parts.step         the three as three solids of one file: sphere at (0, 0, 0), torus at
//                      (4, 0, 0), box centred at (8, 0, 0)
//   trimmed.step       three solids whose faces are genuinely trimmed: the slab
//                      [-1, 1]² × [-0.5, 0.5] with a through hole of radius 0.5 about z (two
//                      planar faces with a circular inner loop, a cylinder face inside) at the
//                      origin; the cylinder of radius 0.5, |z| ≤ 0.5 (planar faces bounded by a
//                      circle) about (4, 0, z); the unit sphere at (8, 0, 0) cut by the plane
//                      n·(p − c) = 0.4, n = (1, 1, 1)/√3 (a spherical face trimmed by a circle
//                      that is no parameter line, and a planar disc)
//   open_shell.step    one planar face [0, 1]² (z = 0), no solid: an error case
//   open_solid.step    a solid whose shell is the box [0, 1]³ without its top face (free
//                      edges): an error case
// Units: millimetres (OCCT's default), as the importer reads them. The header's time
// stamp is fixed so that running it again gives the same bytes.
// Build and run (needs CISAMR_WITH_OCCT):
//   ninja -C build make_step_shapes && cd data/shapes && ../../build/lib/geometry/make_step_shapes
#include <APIHeaderSection_MakeHeader.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_Transform.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeHalfSpace.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <StepData_StepModel.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <gp_Pln.hxx>
#include <gp_Trsf.hxx>

#include <cstdio>
#include <initializer_list>
#include <string>

namespace {

TopoDS_Shape sphere() { return BRepPrimAPI_MakeSphere(1.0).Shape(); }
TopoDS_Shape torus() { return BRepPrimAPI_MakeTorus(1.0, 0.3).Shape(); }

TopoDS_Shape filleted_box() {
  BRepPrimAPI_MakeBox box(gp_Pnt(-1, -1, -1), 2.0, 2.0, 2.0);
  BRepFilletAPI_MakeFillet fillet(box.Shape());
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(box.Shape(), TopAbs_EDGE, edges);
  for (int i = 1; i <= edges.Extent(); ++i) fillet.Add(0.3, TopoDS::Edge(edges(i)));
  fillet.Build();
  if (!fillet.IsDone()) throw Standard_Failure("fillet failed");
  return fillet.Shape();
}

TopoDS_Shape cut(const TopoDS_Shape& a, const TopoDS_Shape& b) {
  BRepAlgoAPI_Cut op(a, b);
  if (!op.IsDone()) throw Standard_Failure("boolean cut failed");
  return op.Shape();
}

TopoDS_Shape cylinder(double r, double z0, double height) {
  return BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, z0), gp::DZ()), r, height).Shape();
}

TopoDS_Shape holed_slab() { return cut(BRepPrimAPI_MakeBox(gp_Pnt(-1, -1, -0.5), 2.0, 2.0, 1.0).Shape(), cylinder(0.5, -1.0, 2.0)); }

TopoDS_Shape cut_sphere() {
  const gp_Dir n(1, 1, 1);
  const gp_Pnt on(0.4 * n.X(), 0.4 * n.Y(), 0.4 * n.Z());
  const TopoDS_Face plane = BRepBuilderAPI_MakeFace(gp_Pln(on, n)).Face();
  const TopoDS_Shape beyond = BRepPrimAPI_MakeHalfSpace(plane, gp_Pnt(2 * n.X(), 2 * n.Y(), 2 * n.Z())).Solid();
  return cut(sphere(), beyond);
}

TopoDS_Shape moved(const TopoDS_Shape& s, double x) {
  gp_Trsf t;
  t.SetTranslation(gp_Vec(x, 0, 0));
  return BRepBuilderAPI_Transform(s, t, /*copy*/ true).Shape();
}

TopoDS_Shape open_solid() {
  BRepPrimAPI_MakeBox box(1.0, 1.0, 1.0);
  BRep_Builder b;
  TopoDS_Shell shell;
  b.MakeShell(shell);
  const TopoDS_Face top = box.TopFace();
  for (TopExp_Explorer f(box.Shape(), TopAbs_FACE); f.More(); f.Next())
    if (!f.Current().IsSame(top)) b.Add(shell, f.Current());
  TopoDS_Solid solid;
  b.MakeSolid(solid);
  b.Add(solid, shell);
  return solid;
}

bool write(const std::string& path, std::initializer_list<TopoDS_Shape> shapes,
           STEPControl_StepModelType mode = STEPControl_AsIs) {
  STEPControl_Writer writer;
  Interface_Static::SetCVal("write.step.schema", "AP214IS");
  Interface_Static::SetCVal("write.step.unit", "MM");
  for (const TopoDS_Shape& s : shapes)
    if (writer.Transfer(s, mode) != IFSelect_RetDone) return false;
  APIHeaderSection_MakeHeader header(writer.Model());
  header.SetName(new TCollection_HAsciiString(path.c_str()));
  header.SetTimeStamp(new TCollection_HAsciiString("2025-01-01T00:00:00"));
  return writer.Write(path.c_str()) == IFSelect_RetDone;
}

}  // namespace

int main() {
  Message::DefaultMessenger()->ChangePrinters().Clear();  // no transfer statistics
  try {
    const TopoDS_Shape s = sphere(), t = torus(), b = filleted_box();
    bool ok = write("sphere.step", {s}) && write("torus.step", {t}) && write("filleted_box.step", {b}) &&
              write("parts.step", {s, moved(t, 4.0), moved(b, 8.0)});
    const TopoDS_Face face = BRepBuilderAPI_MakeFace(gp_Pln(gp::XOY()), 0.0, 1.0, 0.0, 1.0).Face();
    ok = ok && write("trimmed.step", {holed_slab(), moved(cylinder(0.5, -0.5, 1.0), 4.0), moved(cut_sphere(), 8.0)});
    ok = ok && write("open_shell.step", {face}) && write("open_solid.step", {open_solid()});
    if (!ok) {
      std::fprintf(stderr, "make_step: a STEP transfer or write failed\n");
      return 1;
    }
  } catch (const Standard_Failure& e) {
    std::fprintf(stderr, "make_step: %s\n", e.GetMessageString());
    return 1;
  }
  std::printf("wrote sphere.step torus.step filleted_box.step parts.step trimmed.step open_shell.step open_solid.step\n");
  return 0;
}

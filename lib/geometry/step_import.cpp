// STEP import through OpenCASCADE 7.6 (docs/nurbs-step-design.md §3.2, §4.2): the only
// translation unit of cisamr that includes OCCT. Built with CISAMR_WITH_OCCT only.
//
// 1. under one mutex for the whole import (Interface_Static is global), OCCT's default
//    printers removed once (the library never prints), xstep.cascade.unit = MM;
// 2. STEPControl_Reader::ReadStream; load and transfer fails name the entity;
// 3. the solids in TopExp_Explorer order; faces outside every solid, or free edges in a
//    solid's shells (ShapeAnalysis_FreeBounds), are an open shell;
// 4. per solid, BRepBuilderAPI_NurbsConvert: each face's surface (location applied)
//    made non-periodic and copied to a NurbsPatch, each wire a closed loop of B-spline
//    pcurves;
// 5. BRepMesh on the converted solid (sequential), nodes welded by exact coordinates;
// 6. BRepGProp volume, BRepBndLib box.
#include "geometry/step_import.hpp"

#include <BRepBndLib.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRepTools_WireExplorer.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Geom2dConvert.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_TrimmedCurve.hxx>
#include <GeomConvert.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_RectangularTrimmedSurface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Check.hxx>
#include <Interface_CheckIterator.hxx>
#include <Interface_InterfaceModel.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_Printer.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeAnalysis_FreeBounds.hxx>
#include <Standard_Failure.hxx>
#include <StepSelect_StepType.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Wire.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <mutex>
#include <sstream>
#include <utility>

namespace cisamr::geometry {
namespace {

std::mutex import_mutex;  // OCCT's static settings (Interface_Static) are process-wide

// A problem found on the way: the message after "name: ".
struct Problem {
  std::string text;
};

std::string str(std::size_t n) { return std::to_string(n); }

std::string failure_text(const Standard_Failure& e) {
  const char* what = e.GetMessageString();
  std::string text = e.DynamicType()->Name();
  if (what != nullptr && *what != '\0') text += std::string(": ") + what;
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

// Keeps what OCCT reports while the file is parsed (its default printers are removed):
// the STEP parser says where the syntax fails only there.
class Capture : public Message_Printer {
 public:
  mutable std::vector<std::string> lines;  // warnings and worse, in order

 protected:
  void send(const TCollection_AsciiString& text, const Message_Gravity gravity) const override {
    if (gravity < Message_Warning || lines.size() >= 16) return;
    std::string line = text.ToCString();
    for (char& c : line)
      if (c == '\n' || c == '\r' || c == '\t') c = ' ';
    // "**** ERR StepFile : Undefined Parsing: Line 2: Incorrect syntax: … ****" → "Line 2: …"
    while (!line.empty() && (line.back() == ' ' || line.back() == '*')) line.pop_back();
    std::size_t start = line.find_first_not_of("* ");
    line.erase(0, start == std::string::npos ? line.size() : start);
    for (const char* prefix : {"ERR StepFile : ", "Undefined Parsing: "})
      if (line.rfind(prefix, 0) == 0) line.erase(0, std::string(prefix).size());
    if (!line.empty()) lines.push_back(line);
  }
};

// The first failing check of `checks` as "entity #12 (ADVANCED_FACE): text", or "".
std::string first_fail(const Interface_CheckIterator& checks, const Handle(Interface_InterfaceModel)& model,
                       const Handle(Interface_Protocol)& protocol) {
  for (Interface_CheckIterator it = checks; it.More(); it.Next()) {
    const Handle(Interface_Check)& check = it.Value();
    if (check.IsNull() || !check->HasFailed()) continue;
    std::string text = check->NbFails() > 0 ? check->CFail(1) : "failed";
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    Handle(Standard_Transient) entity = check->HasEntity() ? check->Entity() : Handle(Standard_Transient)();
    if (entity.IsNull() && it.Number() > 0 && !model.IsNull() && it.Number() <= model->NbEntities())
      entity = model->Value(it.Number());
    if (entity.IsNull() || model.IsNull()) return text;
    std::string label = "#" + std::to_string(it.Number());
    if (const Handle(TCollection_HAsciiString) l = model->StringLabel(entity); !l.IsNull()) label = l->ToCString();
    std::string type;
    if (!protocol.IsNull()) {
      Handle(StepSelect_StepType) signature = new StepSelect_StepType;
      signature->SetProtocol(protocol);
      if (const char* t = signature->Value(entity, model)) type = t;
    }
    return "entity " + label + (type.empty() ? "" : " (" + type + ")") + ": " + text;
  }
  return "";
}

BrepCurve2 to_curve(const Handle(Geom2d_BSplineCurve)& c) {
  BrepCurve2 out;
  out.degree = c->Degree();
  const int n = c->NbPoles();
  TColStd_Array1OfReal knots(1, c->NbPoles() + c->Degree() + 1);
  c->KnotSequence(knots);
  for (int i = knots.Lower(); i <= knots.Upper(); ++i) out.knots.push_back(knots(i));
  for (int i = 1; i <= n; ++i) {
    const gp_Pnt2d p = c->Pole(i);
    out.control_points.push_back({p.X(), p.Y()});
    out.weights.push_back(c->Weight(i));
  }
  return out;
}

NurbsPatch to_patch(const Handle(Geom_BSplineSurface)& s) {
  NurbsPatch out;
  out.degree = {s->UDegree(), s->VDegree()};
  const int nu = s->NbUPoles(), nv = s->NbVPoles();
  TColStd_Array1OfReal ku(1, nu + s->UDegree() + 1), kv(1, nv + s->VDegree() + 1);
  s->UKnotSequence(ku);
  s->VKnotSequence(kv);
  for (int i = ku.Lower(); i <= ku.Upper(); ++i) out.knots_u.push_back(ku(i));
  for (int i = kv.Lower(); i <= kv.Upper(); ++i) out.knots_v.push_back(kv(i));
  // OCCT's pole (i, j) has i along u: u fastest is j outer, i inner.
  const TColgp_Array2OfPnt& poles = s->Poles();
  out.control_points.reserve(static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv));
  out.weights.reserve(out.control_points.capacity());
  for (int j = 1; j <= nv; ++j)
    for (int i = 1; i <= nu; ++i) {
      const gp_Pnt& p = poles(poles.LowerRow() + i - 1, poles.LowerCol() + j - 1);
      out.control_points.push_back({p.X(), p.Y(), p.Z()});
      out.weights.push_back(s->Weight(i, j));
    }
  return out;
}

// The face's surface as a non-periodic B-spline in the face's own parametrisation.
Handle(Geom_BSplineSurface) bspline_surface(const TopoDS_Face& face, const std::string& where) {
  const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);  // location applied
  if (surface.IsNull()) throw Problem{where + ": has no surface"};
  Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(surface);
  if (!bs.IsNull()) {
    bs = Handle(Geom_BSplineSurface)::DownCast(bs->Copy());  // never modify the shape's own
  } else {
    // A plane left by NurbsConvert: over the face's uv bounds its B-spline form keeps the
    // parametrisation (degree 1 × 1, linear). Any other surface would be reparametrised.
    Handle(Geom_Surface) basis = surface;
    if (const auto t = Handle(Geom_RectangularTrimmedSurface)::DownCast(basis); !t.IsNull()) basis = t->BasisSurface();
    if (Handle(Geom_Plane)::DownCast(basis).IsNull())
      throw Problem{where + ": cannot be converted to a B-spline surface (" + surface->DynamicType()->Name() + ")"};
    double u0, u1, v0, v1;
    BRepTools::UVBounds(face, u0, u1, v0, v1);
    bs = GeomConvert::SurfaceToBSplineSurface(new Geom_RectangularTrimmedSurface(basis, u0, u1, v0, v1));
    if (bs.IsNull()) throw Problem{where + ": cannot be converted to a B-spline surface (plane)"};
  }
  // A periodic B-spline made non-periodic keeps its knots, unclamped (0 and 2π of
  // multiplicity 2 for degree 2, the outer knots −2π/3 and 8π/3 of multiplicity 1): clamp
  // it over the same bounds (knot insertion to the degree there: the poles stay).
  if (bs->IsUPeriodic()) bs->SetUNotPeriodic();
  if (bs->IsVPeriodic()) bs->SetVNotPeriodic();
  const bool clamped_u = bs->UMultiplicity(1) == bs->UDegree() + 1 && bs->UMultiplicity(bs->NbUKnots()) == bs->UDegree() + 1;
  const bool clamped_v = bs->VMultiplicity(1) == bs->VDegree() + 1 && bs->VMultiplicity(bs->NbVKnots()) == bs->VDegree() + 1;
  if (!clamped_u || !clamped_v) {
    double u0, u1, v0, v1;
    bs->Bounds(u0, u1, v0, v1);
    bs->Segment(u0, u1, v0, v1);
  }
  return bs;
}

// The wires of `face` (taken FORWARD: loops follow du × dv) as loops of B-spline pcurves.
std::vector<std::vector<BrepCurve2>> face_loops(const TopoDS_Face& face, const std::string& where) {
  std::vector<std::vector<BrepCurve2>> loops;
  const TopoDS_Face forward = TopoDS::Face(face.Oriented(TopAbs_FORWARD));
  std::size_t w = 0;
  for (TopExp_Explorer wires(forward, TopAbs_WIRE); wires.More(); wires.Next(), ++w) {
    std::vector<BrepCurve2> loop;
    std::size_t e = 0;
    for (BRepTools_WireExplorer edges(TopoDS::Wire(wires.Current()), forward); edges.More(); edges.Next(), ++e) {
      const TopoDS_Edge& edge = edges.Current();
      double first = 0, last = 0;
      const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(edge, forward, first, last);
      if (pcurve.IsNull())
        throw Problem{where + ": wire " + str(w) + " edge " + str(e) + " has no curve on the face"};
      Handle(Geom2d_BSplineCurve) c = Geom2dConvert::CurveToBSplineCurve(new Geom2d_TrimmedCurve(pcurve, first, last));
      if (c.IsNull())
        throw Problem{where + ": wire " + str(w) + " edge " + str(e) + ": cannot convert its curve on the face"};
      if (c->IsPeriodic()) c->SetNotPeriodic();
      if (c->Multiplicity(1) != c->Degree() + 1 || c->Multiplicity(c->NbKnots()) != c->Degree() + 1)
        c->Segment(c->FirstParameter(), c->LastParameter());
      if (edge.Orientation() == TopAbs_REVERSED) c->Reverse();
      loop.push_back(to_curve(c));
    }
    if (!loop.empty()) loops.push_back(std::move(loop));
  }
  return loops;
}

double shape_tolerance(const TopoDS_Shape& face) {
  double t = 0;
  for (TopExp_Explorer e(face, TopAbs_EDGE); e.More(); e.Next()) t = std::max(t, BRep_Tool::Tolerance(TopoDS::Edge(e.Current())));
  for (TopExp_Explorer v(face, TopAbs_VERTEX); v.More(); v.Next())
    t = std::max(t, BRep_Tool::Tolerance(TopoDS::Vertex(v.Current())));
  return t;
}

std::size_t edge_count(const TopoDS_Shape& s) {
  TopTools_IndexedMapOfShape edges;
  TopExp::MapShapes(s, TopAbs_EDGE, edges);
  return static_cast<std::size_t>(edges.Extent());
}

BrepSolid convert_solid(const TopoDS_Shape& solid, const std::string& where) {
  BrepSolid out;
  BRepBuilderAPI_NurbsConvert convert(solid, /*Copy*/ Standard_True);
  if (!convert.IsDone()) throw Problem{where + ": conversion to B-spline faces failed"};
  const TopoDS_Shape converted = convert.Shape();

  Bnd_Box bounds;  // of the solid as read: analytic faces are bounded in closed form
  BRepBndLib::AddOptimal(solid, bounds, /*useTriangulation*/ Standard_False, /*useShapeTolerance*/ Standard_False);
  if (bounds.IsVoid()) throw Problem{where + ": empty"};
  double x0, y0, z0, x1, y1, z1;
  bounds.Get(x0, y0, z0, x1, y1, z1);
  out.box = {{x0, y0, z0}, {x1, y1, z1}};
  const double diagonal = std::sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0) + (z1 - z0) * (z1 - z0));

  BRepMesh_IncrementalMesh mesher(converted, 2e-3 * diagonal, /*isRelative*/ Standard_False, /*angle*/ 0.3,
                                  /*isInParallel*/ Standard_False);
  if (!mesher.IsDone()) throw Problem{where + ": meshing failed"};

  std::map<Vec3, std::int32_t> welded;  // exact coordinates (−0 and +0 compare equal)
  std::size_t f = 0;
  for (TopExp_Explorer faces(converted, TopAbs_FACE); faces.More(); faces.Next(), ++f) {
    const TopoDS_Face& face = TopoDS::Face(faces.Current());
    const std::string at = where + " face " + str(f);
    BrepFace bf;
    try {
      bf.surface = to_patch(bspline_surface(face, at));
      bf.loops = face_loops(face, at);
    } catch (const Standard_Failure& e) {
      throw Problem{at + ": cannot be converted (" + failure_text(e) + ")"};
    }
    bf.tolerance = BRep_Tool::Tolerance(face);
    bf.edge_tolerance = shape_tolerance(face);
    bf.reversed = face.Orientation() == TopAbs_REVERSED;

    TopLoc_Location location;
    const Handle(Poly_Triangulation) mesh = BRep_Tool::Triangulation(face, location);
    if (mesh.IsNull() || mesh->NbTriangles() == 0) throw Problem{at + ": not meshed"};
    if (!mesh->HasUVNodes()) throw Problem{at + ": its mesh has no (u, v) nodes"};
    const gp_Trsf& move = location.Transformation();
    const bool moved = !location.IsIdentity();
    std::vector<std::int32_t> node(static_cast<std::size_t>(mesh->NbNodes()) + 1, -1);
    for (int i = 1; i <= mesh->NbNodes(); ++i) {
      gp_Pnt p = mesh->Node(i);
      if (moved) p.Transform(move);
      const Vec3 x{p.X(), p.Y(), p.Z()};
      const auto [it, inserted] = welded.emplace(x, static_cast<std::int32_t>(out.vertices.size()));
      if (inserted) out.vertices.push_back(x);
      node[static_cast<std::size_t>(i)] = it->second;
    }
    for (int t = 1; t <= mesh->NbTriangles(); ++t) {
      int a = 0, b = 0, c = 0;
      mesh->Triangle(t).Get(a, b, c);
      if (bf.reversed) std::swap(b, c);
      const std::int32_t na = node[static_cast<std::size_t>(a)], nb = node[static_cast<std::size_t>(b)],
                         nc = node[static_cast<std::size_t>(c)];
      if (na == nb || nb == nc || nc == na) continue;  // degenerate at a pole
      const gp_Pnt2d ua = mesh->UVNode(a), ub = mesh->UVNode(b), uc = mesh->UVNode(c);
      out.triangles.push_back({na, nb, nc});
      out.triangle_face.push_back(static_cast<std::int32_t>(f));
      out.triangle_uv.push_back({Vec2{ua.X(), ua.Y()}, Vec2{ub.X(), ub.Y()}, Vec2{uc.X(), uc.Y()}});
    }
    out.faces.push_back(std::move(bf));
  }
  if (out.faces.empty()) throw Problem{where + ": has no face"};
  for (const Vec3& v : out.vertices)
    for (int d = 0; d < 3; ++d) {
      out.box.min[d] = std::min(out.box.min[d], v[d]);
      out.box.max[d] = std::max(out.box.max[d], v[d]);
    }

  // On the solid as read: the converted faces bound the same volume (the conversion of
  // elementary surfaces is exact), but OCCT integrates rational B-spline faces poorly
  // (the converted unit sphere: 4e-4 off by default, 1e-9 adaptively).
  GProp_GProps properties;
  BRepGProp::VolumeProperties(solid, properties, /*Eps*/ 1e-12);
  out.volume = properties.Mass();
  return out;
}

std::string import_locked(std::string_view bytes, const std::string& name, BrepData& out) {
  static bool quiet = false;
  if (!quiet) {
    Message::DefaultMessenger()->ChangePrinters().Clear();
    quiet = true;
  }
  if (bytes.empty()) return "empty file, not a STEP file";
  STEPControl_Reader reader;  // initialises the STEP controller and its static settings
  Interface_Static::SetCVal("xstep.cascade.unit", "MM");
  std::istringstream stream{std::string(bytes)};
  const Handle(Capture) capture = new Capture;
  capture->SetTraceLevel(Message_Trace);
  Message::DefaultMessenger()->AddPrinter(capture);
  IFSelect_ReturnStatus status = IFSelect_RetFail;
  try {
    status = reader.ReadStream(name.c_str(), stream);
  } catch (...) {
    Message::DefaultMessenger()->RemovePrinter(capture);
    throw;
  }
  Message::DefaultMessenger()->RemovePrinter(capture);
  const Handle(XSControl_WorkSession) session = reader.WS();
  const Handle(Interface_InterfaceModel) model = session->Model();
  if (status != IFSelect_RetDone || model.IsNull() || model->NbEntities() == 0) {
    std::string why;
    for (const std::string& line : capture->lines) why += (why.empty() ? "" : "; ") + line;
    return "not a readable STEP file" + (why.empty() ? std::string() : " (" + why + ")");
  }
  if (std::string fail = first_fail(session->ModelCheckList(), model, session->Protocol()); !fail.empty())
    return fail;

  reader.TransferRoots();
  if (std::string fail = first_fail(session->TransferReader()->LastCheckList(), model, session->Protocol());
      !fail.empty())
    return fail;
  const TopoDS_Shape shape = reader.OneShape();

  TopTools_IndexedMapOfShape solid_faces;
  std::vector<TopoDS_Shape> solids;
  for (TopExp_Explorer s(shape, TopAbs_SOLID); s.More(); s.Next()) {
    solids.push_back(s.Current());
    TopExp::MapShapes(s.Current(), TopAbs_FACE, solid_faces);
  }
  TopTools_IndexedMapOfShape all_faces;
  TopExp::MapShapes(shape, TopAbs_FACE, all_faces);
  const std::size_t free_faces = static_cast<std::size_t>(all_faces.Extent() - solid_faces.Extent());
  if (solids.empty())
    return free_faces == 0 ? "no solid"
                           : "no solid (open shell: " + str(free_faces) + (free_faces == 1 ? " face" : " faces") +
                                 " bounding no volume)";
  if (free_faces > 0)
    return "open shell: " + str(free_faces) + (free_faces == 1 ? " face belongs" : " faces belong") + " to no solid";
  for (std::size_t k = 0; k < solids.size(); ++k) {
    ShapeAnalysis_FreeBounds bounds(solids[k], /*splitclosed*/ Standard_False, /*splitopen*/ Standard_False);
    const std::size_t free_edges = edge_count(bounds.GetClosedWires()) + edge_count(bounds.GetOpenWires());
    if (free_edges > 0)
      return "solid " + str(k) + ": open shell (" + str(free_edges) + (free_edges == 1 ? " free edge)" : " free edges)");
  }

  BrepData data;
  for (std::size_t k = 0; k < solids.size(); ++k) data.solids.push_back(convert_solid(solids[k], "solid " + str(k)));
  out = std::move(data);
  return "";
}

}  // namespace

bool step_import_available() { return true; }

std::string import_step(std::string_view bytes, const std::string& name, BrepData& out) {
  out = BrepData{};
  std::string problem;
  {
    const std::lock_guard<std::mutex> lock(import_mutex);
    try {
      problem = import_locked(bytes, name, out);
    } catch (const Problem& p) {
      problem = p.text;
    } catch (const Standard_Failure& e) {
      problem = "OpenCASCADE failed (" + failure_text(e) + ")";
    } catch (const std::exception& e) {
      problem = std::string("OpenCASCADE failed (") + e.what() + ")";
    }
  }
  if (problem.empty()) return "";
  out = BrepData{};
  return name + ": " + problem;
}

}  // namespace cisamr::geometry

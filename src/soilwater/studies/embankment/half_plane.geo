// A half-plane 400 m x 200 m (the symmetry half) under the embankment's load, nodes
// 0.5 m apart near the load growing to 24 m: the first loading stage of the built-in
// "embankment" against the closed form of soilwater.references.closed_forms
// (surface_load_pressure): soilwater.studies.embankment.study.first_stage.
// Mesh with: gmsh -2 -format msh41 half_plane.geo
Point(1) = {0, 0, 0, 24};
Point(2) = {400, 0, 0, 24};
Point(3) = {400, 200, 0, 24};
Point(4) = {15, 200, 0, 0.5};
Point(5) = {5, 200, 0, 0.5};
Point(6) = {0, 200, 0, 0.5};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Field[1] = Distance;
Field[1].CurvesList = {4, 5};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.5;
Field[2].SizeMax = 24.0;
Field[2].DistMin = 3.0;
Field[2].DistMax = 160.0;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Physical Curve("base") = {1};
Physical Curve("far") = {2};
Physical Curve("surface") = {3, 4, 5};
Physical Curve("axis") = {6};
Physical Surface("soil") = {1};

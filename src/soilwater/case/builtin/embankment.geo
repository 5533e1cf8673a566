// The built-in case "embankment" (embankment.toml): a fill on a crust over soft clay.
// Foundation 40 m wide (the symmetry half) and 12 m deep: crust 2 m over soft clay 10 m.
// The fill's footprint on the ground surface: crest half-width 5 m, slopes down to the
// toe at x = 15 m. Nodes 0.4 m apart at the toe, growing to 3 m far off.
// Mesh with: gmsh -2 -format msh41 embankment.geo
Point(1) = {0, 0, 0, 2.0};
Point(2) = {40, 0, 0, 3.0};
Point(3) = {40, 10, 0, 3.0};
Point(4) = {40, 12, 0, 3.0};
Point(5) = {15, 12, 0, 0.4};
Point(6) = {5, 12, 0, 0.6};
Point(7) = {0, 12, 0, 0.8};
Point(8) = {0, 10, 0, 0.8};
Point(9) = {15, 10, 0, 0.5};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 8};
Line(8) = {8, 1};
Line(9) = {8, 9};
Line(10) = {9, 3};
Curve Loop(1) = {1, 2, -10, -9, 8};
Plane Surface(1) = {1};
Curve Loop(2) = {9, 10, 3, 4, 5, 6, 7};
Plane Surface(2) = {2};
Field[1] = Distance;
Field[1].PointsList = {5, 6, 9};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.4;
Field[2].SizeMax = 3.0;
Field[2].DistMin = 2.0;
Field[2].DistMax = 20.0;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Physical Curve("base") = {1};
Physical Curve("axis") = {7, 8};
Physical Curve("far") = {2, 3};
Physical Curve("surface") = {4, 5, 6};
Physical Surface("clay") = {1};
Physical Surface("crust") = {2};

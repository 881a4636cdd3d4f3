//! Reading and writing STL, OBJ and PLY meshes.

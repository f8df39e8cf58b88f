#pragma once

// A COLLADA (.dae) file's geometry, read with libxml2 and checked before
// libassimp sees any of it: assimp 5.2's COLLADA reader trusts the file's
// counts, references and indices, and a wrong one made it follow a null
// pointer, abort on an assertion or ask for gigabytes (each a find of the mesh
// fuzz target). What assimp reads instead is a plain document written here.

#include <string>

namespace rise::sim {

/// The geometry of the COLLADA document `bytes`, written anew as a plain
/// COLLADA 1.4.1 document: the asset's unit and up axis; each mesh's
/// positions and its <triangles> and <polylist> vertex indices; the visual
/// scene's node tree with its transforms and geometry instances. Everything
/// else (materials, normals, texture coordinates, cameras, lights,
/// animation, controllers) is left out, and every id is the writer's own.
/// Each array's count matches its numbers, each accessor lies inside its
/// array, each reference names an element of its kind, each index names a
/// position and each number is finite. Throws std::runtime_error
/// "<where>:<line>: <what>" for a document that is not so, or whose meaning
/// would be lost here (<instance_node>, <lookat>, <skew>).
std::string plain_collada(const std::string& bytes, const std::string& where);

}  // namespace rise::sim

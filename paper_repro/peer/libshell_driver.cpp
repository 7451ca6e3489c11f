// Driver for the peer comparison (paper_repro/peer/README.md): the two kshell benchmark
// problems, the heavy ASTM D1388 cantilever and the linear square plate, solved with the
// discrete-shell energies of libshell (https://github.com/evouga/libshell, commit 6072d9e).
//
// Our own code: it calls libshell's public API only (MeshConnectivity, ElasticShell, StVKMaterial
// and a second-fundamental-form class: MidedgeAngleTanFormulation by default, libshell's
// recommendation) for the elastic energy, its gradient and its Hessian. Mesh generation,
// boundary conditions, loads and the Newton solver below are ours. Build and run:
// paper_repro/peer/run.sh.
//
// Usage:
//   libshell_driver cantilever NX NY [options]
//   libshell_driver plate N simple|clamped [options]
//   libshell_driver check        (bending-energy scaling check on a cylinder)
// (options: run it without arguments). Prints one CSV line:
//   problem,mesh,vertices,free_dofs,qoi,rel_error,load_steps,newton_iterations,setup_s,solve_s
// and, with -v, the Newton iterations and a time split on stderr.

#include "ElasticShell.h"
#include "MeshConnectivity.h"
#include "MidedgeAngleSinFormulation.h"
#include "MidedgeAngleTanFormulation.h"
#include "MidedgeAverageFormulation.h"
#include "RestState.h"
#include "StVKMaterial.h"
#include "types.h"

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;
using LibShell::HessianProjectType;

static double seconds_since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A structured triangle mesh of the rectangle [x0, x0 + nx hx] x [y0, y0 + ny hy], each cell
// cut along a diagonal whose direction alternates in a checkerboard (the mesh is symmetric
// about the mid-lines when nx and ny are even). Vertex (i, j) has index j (nx + 1) + i.
static bool g_uniformDiagonals = false;  // --pattern uniform: every cell cut along a-d

static void grid(int nx, int ny, double x0, double y0, double hx, double hy,
                 Eigen::MatrixXd& V, Eigen::MatrixXi& F) {
    V.resize((nx + 1) * (ny + 1), 3);
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++)
            V.row(j * (nx + 1) + i) << x0 + i * hx, y0 + j * hy, 0.0;
    F.resize(2 * nx * ny, 3);
    int f = 0;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;  // a b bottom, c d top
            if (g_uniformDiagonals || (i + j) % 2 == 0) {  // diagonal a-d
                F.row(f++) << a, b, d;
                F.row(f++) << a, d, c;
            } else {  // diagonal b-c
                F.row(f++) << a, b, c;
                F.row(f++) << b, d, c;
            }
        }
}

// Options shared by the problems.
struct Options {
    double rtol = 1e-10;
    std::string sff = "tan";  // second fundamental form: tan (libshell's recommendation), sin, average
    double ghostStiffness = 1e6;  // clamp of the angle formulations: ghost faces' bending stiffness / shell's
    int steps = 0;                // load steps (0: whole load first, then adaptive steps)
    int maxit = 60;               // Newton iterations per solve
    int fullStepIterations = 25;  // first the whole load by full-step Newton, at most this many iterations (0: skip)
    bool verbose = false;
};
static Options g_opt;
static double g_hessianSeconds = 0, g_factorSeconds = 0;  // reported with -v

template <class SFF>
static bool edge_dofs_valid(const LibShell::MeshConnectivity&, const Eigen::MatrixXd&, const Eigen::VectorXd&) {
    return true;
}
template <>
bool edge_dofs_valid<LibShell::MidedgeAngleTanFormulation>(const LibShell::MeshConnectivity& mesh,
                                                          const Eigen::MatrixXd& pos, const Eigen::VectorXd& e) {
    return LibShell::MidedgeAngleTanFormulation::edgeDOFsValid(mesh, pos, e);
}

// A shell problem: flat rest state, StVK material, a dead load (forces on the vertex DOFs,
// scaled by the load factor), fixed DOFs. The unknowns q are the vertex positions (3|V|, vertex
// by vertex) followed by the formulation's edge DOFs (director angles; none for "average").
template <class SFF>
struct Problem {
    using Shell = LibShell::ElasticShell<SFF>;
    LibShell::MeshConnectivity mesh;
    Eigen::MatrixXd rest;  // |V| x 3
    LibShell::MonolayerRestState rs;
    LibShell::StVKMaterial<SFF> mat;
    Eigen::VectorXd q0;              // rest positions and initial edge DOFs
    Eigen::VectorXd fext;            // full load
    std::vector<int> freeIndex;      // DOF -> free index or -1
    int nv = 0, ndof = 0, nfree = 0;

    void init(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F, const std::vector<double>& thick,
              double young, double poisson) {
        mesh = LibShell::MeshConnectivity(F);
        rest = V;
        nv = (int)V.rows();
        Eigen::VectorXd e;
        SFF::initializeExtraDOFs(e, mesh, rest);
        ndof = 3 * nv + (int)e.size();
        q0.resize(ndof);
        for (int v = 0; v < nv; v++) q0.segment<3>(3 * v) = V.row(v).transpose();
        q0.tail(e.size()) = e;
        rs.thicknesses = thick;
        Shell::firstFundamentalForms(mesh, rest, rs.abars);
        rs.bbars.assign(mesh.nFaces(), Eigen::Matrix2d::Zero());
        // plane-stress Lame parameters, as in libshell's example program
        rs.lameAlpha.assign(mesh.nFaces(), young * poisson / (1.0 - poisson * poisson));
        rs.lameBeta.assign(mesh.nFaces(), young / 2.0 / (1.0 + poisson));
        fext = Eigen::VectorXd::Zero(ndof);
        freeIndex.assign(ndof, 0);
    }
    void number_free() {
        nfree = 0;
        for (auto& k : freeIndex) k = (k < 0) ? -1 : nfree++;
    }
    double face_area(int f) const { return 0.5 * std::sqrt(rs.abars[f].determinant()); }
    Eigen::MatrixXd positions(const Eigen::VectorXd& q) const {
        Eigen::MatrixXd pos(nv, 3);
        for (int v = 0; v < nv; v++) pos.row(v) = q.segment<3>(3 * v).transpose();
        return pos;
    }
    // Total potential energy at load factor lam (inf where the edge DOFs leave the formulation's
    // domain); gradient over all DOFs, elastic part of it, Hessian triplets.
    double energy(const Eigen::VectorXd& q, double lam, Eigen::VectorXd* gradAll, Eigen::VectorXd* gradElastic,
                  std::vector<Eigen::Triplet<double>>* trip, HessianProjectType proj) const {
        Eigen::MatrixXd pos = positions(q);
        Eigen::VectorXd e = q.tail(ndof - 3 * nv), g;
        if (!edge_dofs_valid<SFF>(mesh, pos, e)) return std::numeric_limits<double>::infinity();
        double E = Shell::elasticEnergy(mesh, pos, e, mat, rs, gradAll ? &g : nullptr, trip, proj);
        if (gradElastic) *gradElastic = g;
        if (gradAll) *gradAll = g - lam * fext;
        return E - lam * fext.dot(q - q0);
    }
};

struct SolveStats {
    int loadSteps = 0;
    int iterations = 0;
    bool ok = false;
};

// Newton on the free DOFs: Eigen's SimplicialLDLT on the exact Hessian; where that is not
// positive definite (or gives no descent direction) the per-element Hessians are projected to
// be positive semi-definite (libshell's kMaxZero) and, if still needed, a diagonal shift is
// added. Backtracking (Armijo) line search on the total energy, or (fullSteps) full steps,
// shortened only where the energy is undefined. Converged when
// |g_free| <= rtol (|elastic force over all DOFs| + |load|), kshell's criterion; below 1e-6 of
// that scale (kshell's STALL_RTOL), an iteration that no longer halves |g_free| or a line search
// that finds no decrease counts as the round-off floor.
template <class SFF>
static bool newton(const Problem<SFF>& P, Eigen::VectorXd& q, double lam, int maxit,
                   Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>& ldlt, bool& analysed, int& iters,
                   bool fullSteps = false) {
    std::vector<Eigen::Triplet<double>> trip, red;
    Eigen::SparseMatrix<double> H(P.nfree, P.nfree);
    Eigen::VectorXd gAll, gEl, gf(P.nfree), d(P.nfree), trial;
    const double loadNorm = lam * P.fext.norm();
    double lastRes = 0;
    for (int it = 0; it < maxit; it++) {
        // energy and gradient; the exact Hessian below only where another step is needed
        double E = P.energy(q, lam, &gAll, &gEl, nullptr, HessianProjectType::kNone);
        for (int k = 0; k < P.ndof; k++)
            if (P.freeIndex[k] >= 0) gf[P.freeIndex[k]] = gAll[k];
        const double scale = gEl.norm() + loadNorm;
        const double res = gf.norm();
        if (g_opt.verbose)
            std::fprintf(stderr, "  load %.4f it %d E %.12e rel.res %.3e\n", lam, it, E, res / scale);
        if (res <= g_opt.rtol * scale) return true;
        // round-off floor: no longer converging, already below 1e-6 (kshell's STALL_RTOL)
        if (it > 0 && res <= 1e-6 * scale && res > 0.5 * lastRes) return true;
        lastRes = res;
        bool solved = false;
        for (int attempt = 0; attempt < 2 && !solved; attempt++) {
            auto th = Clock::now();
            P.energy(q, lam, nullptr, nullptr, &trip,
                     attempt == 0 ? HessianProjectType::kNone : HessianProjectType::kMaxZero);
            g_hessianSeconds += seconds_since(th);
            red.clear();
            red.reserve(trip.size());
            for (const auto& t : trip) {
                int r = P.freeIndex[t.row()], c = P.freeIndex[t.col()];
                if (r >= 0 && c >= 0) red.emplace_back(r, c, t.value());
            }
            H.setFromTriplets(red.begin(), red.end());
            if (!analysed) {
                auto ta = Clock::now();
                ldlt.analyzePattern(H);
                g_factorSeconds += seconds_since(ta);
                analysed = true;
            }
            double shift = 0;
            const double meanDiag = H.diagonal().cwiseAbs().mean();
            for (int s = 0; s < (attempt == 0 ? 1 : 30); s++) {
                Eigen::SparseMatrix<double> Hs = H;
                if (shift > 0)
                    for (int k = 0; k < P.nfree; k++) Hs.coeffRef(k, k) += shift;
                auto tf = Clock::now();
                ldlt.factorize(Hs);
                g_factorSeconds += seconds_since(tf);
                if (ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0) {
                    d = ldlt.solve(-gf);
                    if (d.dot(gf) < 0) {
                        solved = true;
                        break;
                    }
                }
                shift = shift == 0 ? 1e-10 * meanDiag : 4 * shift;
            }
            if (g_opt.verbose && !solved && attempt == 0) std::fprintf(stderr, "  not positive definite: projecting\n");
        }
        iters++;
        if (!solved) return false;
        // backtracking line search
        const double slope = gf.dot(d);
        double alpha = 1.0;
        bool accepted = false;
        for (int ls = 0; ls < 40; ls++) {
            trial = q;
            for (int k = 0; k < P.ndof; k++)
                if (P.freeIndex[k] >= 0) trial[k] += alpha * d[P.freeIndex[k]];
            double Et = P.energy(trial, lam, nullptr, nullptr, nullptr, HessianProjectType::kNone);
            if (std::isfinite(Et) &&
                (fullSteps || Et <= E + 1e-4 * alpha * slope + 16 * std::numeric_limits<double>::epsilon() * std::abs(E))) {
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if (!accepted) return res <= 1e-6 * scale;
        q = trial;
        if (g_opt.verbose) std::fprintf(stderr, "    step %.3e\n", alpha);
    }
    return false;
}

// Globalisation, as kshell's default ("full-step") strategy: first the whole load by full-step
// Newton (at most g_opt.fullStepIterations iterations, steps shortened only where the energy
// is undefined; unlike kshell, the end state's stability is not checked: on the meshes run here
// the drape angles equal those of line-searched solves). If that does not converge: from the
// start again, the whole load by
// line-searched Newton (at most g_opt.maxit iterations; skipped with --steps K), then load
// steps, each from the secant predictor through the last two equilibria: K equal ones, or
// (steps = 0) from 1/8, doubled after a solve in at most 8 iterations, halved after a failed one.
template <class SFF>
static SolveStats solve(const Problem<SFF>& P, Eigen::VectorXd& q) {
    SolveStats st;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
    bool analysed = false;
    const Eigen::VectorXd start = q;
    if (g_opt.fullStepIterations > 0) {
        st.loadSteps = 1;
        if (newton(P, q, 1.0, g_opt.fullStepIterations, ldlt, analysed, st.iterations, true)) {
            st.ok = true;
            return st;
        }
        if (g_opt.verbose) std::fprintf(stderr, "full steps failed: line-searched Newton from the start\n");
        q = start;
    }
    if (g_opt.steps == 0) {
        st.loadSteps++;
        int before = st.iterations;
        if (newton(P, q, 1.0, g_opt.maxit, ldlt, analysed, st.iterations)) {
            st.ok = true;
            return st;
        }
        if (g_opt.verbose) std::fprintf(stderr, "whole load failed after %d iterations: ramping\n", st.iterations - before);
        q = start;
    }
    const bool fixed = g_opt.steps > 0;
    double lam = 0, step = fixed ? 1.0 / g_opt.steps : 0.125, lastStep = 0;
    Eigen::VectorXd prev = q;
    while (lam < 1.0 - 1e-12) {
        double next = std::min(1.0, lam + step);
        Eigen::VectorXd keep = q;
        if (lastStep > 0) {  // secant predictor
            Eigen::VectorXd pred = q + (q - prev) * ((next - lam) / lastStep);
            if (std::isfinite(P.energy(pred, next, nullptr, nullptr, nullptr, HessianProjectType::kNone))) q = pred;
        }
        st.loadSteps++;
        int before = st.iterations;
        if (newton(P, q, next, g_opt.maxit, ldlt, analysed, st.iterations)) {
            prev = keep;
            lastStep = next - lam;
            lam = next;
            if (!fixed && st.iterations - before <= 8) step *= 2;
        } else {
            q = keep;
            if (fixed) return st;
            step *= 0.5;
            if (step < 1e-4) return st;
        }
    }
    st.ok = true;
    return st;
}

// Lumped (area / 3 per vertex) dead load of `perArea` (N/m^2) in -z over the faces of
// nonzero areal mass.
template <class SFF>
static void lumped_z_load(Problem<SFF>& P, const Eigen::MatrixXi& F, const std::vector<bool>& loaded, double perArea) {
    for (int f = 0; f < F.rows(); f++) {
        if (!loaded[f]) continue;
        double a = P.face_area(f);
        for (int j = 0; j < 3; j++) P.fext[3 * F(f, j) + 2] -= perArea * a / 3.0;
    }
}

// Thickness of the ghost faces of a clamp. "average": zero (no energy of their own: the
// boundary hinge's normal is the mean of the flat ghost face's and the shell face's). Angle
// formulations: the edge director is shared by the two faces, so a zero-energy ghost would
// leave it free (a hinge); a ghost face whose bending stiffness is g_opt.ghostStiffness times
// the shell's holds the director on the boundary edge to the ghost's (flat) normal.
static double ghost_thickness(double t) {
    return g_opt.sff == "average" ? 0.0 : t * std::cbrt(g_opt.ghostStiffness);
}

// Fix the edge DOFs of the edges whose faces are all ghosts (nothing to decide there).
template <class SFF>
static void fix_ghost_edges(Problem<SFF>& P, const std::vector<bool>& ghost) {
    const int k = SFF::numExtraDOFs;
    for (int e = 0; e < P.mesh.nEdges(); e++) {
        int f0 = P.mesh.edgeFace(e, 0), f1 = P.mesh.edgeFace(e, 1);
        bool allGhost = (f0 < 0 || ghost[f0]) && (f1 < 0 || ghost[f1]);
        if (allGhost)
            for (int j = 0; j < k; j++) P.freeIndex[3 * P.nv + k * e + j] = -1;
    }
}

static void report(const char* problem, const std::string& meshName, int nv, int nfree, double qoi, double exact,
                   const SolveStats& st, double setup, double solveTime) {
    std::printf("%s,%s,%d,%d,%.10g,%.4e,%d,%d,%.6f,%.6f\n", problem, meshName.c_str(), nv, nfree, qoi,
                qoi / exact - 1.0, st.loadSteps, st.iterations, setup, solveTime);
    if (!st.ok) std::fprintf(stderr, "solve FAILED\n");
    if (g_opt.verbose)
        std::fprintf(stderr, "Hessian assembly %.3f s, symbolic + numeric factorisation %.3f s\n", g_hessianSeconds,
                     g_factorSeconds);
}

// Heavy ASTM D1388 cantilever: strip 25 mm wide, thickness 0.2 mm, E 2e7 Pa, nu 0, 100 g/m^2,
// g 9.80665 m/s^2, overhang 2 c = 47.7349 mm (c = (E t^3 / 12 / (rho g))^(1/3), the bending
// length; exact chord angle 41.4873 deg). The strip lies in y >= 0 and hangs in -z. Clamp: one
// row of ghost faces behind the platform edge (y in [-hy, 0], see ghost_thickness) whose two
// vertex rows are fixed: the edge y = 0 keeps its position and its slope. Drape angle: chord
// from the mid-width point of the edge y = 0 to that of the free end, below horizontal.
template <class SFF>
static int cantilever(int nx, int ny) {
    const double width = 0.025, thick = 2e-4, young = 2e7, poisson = 0, rho = 0.1, g = 9.80665;
    const double overhang = 2.0 * std::cbrt(young * thick * thick * thick / 12.0 / (rho * g));
    const double exact = 41.4873;
    auto t0 = Clock::now();
    const double hx = width / nx, hy = overhang / ny;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    grid(nx, ny + 1, 0.0, -hy, hx, hy, V, F);  // vertex row j = 0 is the platform row y = -hy
    std::vector<bool> ghost(F.rows(), false);
    std::vector<double> th(F.rows(), thick);
    for (int f = 0; f < 2 * nx; f++) {  // the faces of the first cell row
        ghost[f] = true;
        th[f] = ghost_thickness(thick);
    }
    Problem<SFF> P;
    P.init(V, F, th, young, poisson);
    std::vector<bool> loaded(F.rows());
    for (int f = 0; f < F.rows(); f++) loaded[f] = !ghost[f];
    lumped_z_load(P, F, loaded, rho * g);
    for (int i = 0; i < 2 * (nx + 1); i++)
        for (int c = 0; c < 3; c++) P.freeIndex[3 * i + c] = -1;  // vertex rows j = 0, 1
    fix_ghost_edges(P, ghost);
    P.number_free();
    double setup = seconds_since(t0);
    auto t1 = Clock::now();
    Eigen::VectorXd q = P.q0;
    SolveStats st = solve(P, q);
    double solveTime = seconds_since(t1);
    Eigen::MatrixXd pos = P.positions(q);
    // mid-width points (nx even: a vertex; odd: the mean of the two middle vertices)
    auto mid = [&](int j) {
        int r = j * (nx + 1);
        if (nx % 2 == 0) return Eigen::Vector3d(pos.row(r + nx / 2).transpose());
        return Eigen::Vector3d(0.5 * (pos.row(r + nx / 2) + pos.row(r + nx / 2 + 1)).transpose());
    };
    Eigen::Vector3d e = mid(1), tip = mid(ny + 1);
    double angle = std::atan2(-(tip.z() - e.z()), tip.y() - e.y()) * 180.0 / M_PI;
    report("cantilever", std::to_string(nx) + "x" + std::to_string(ny), P.nv, P.nfree, angle, exact, st, setup,
           solveTime);
    return st.ok ? 0 : 1;
}

// Square plate, side 1 m, thickness 0.01 m, E 1e7 Pa, nu 0.3, uniform pressure q = 1e-4 Pa as
// a dead load in -z (linear regime), in-plane DOFs held (bending alone, as in kshell's plate
// scene). Simply supported: the boundary vertices pinned (z = 0) and nothing else; the edge
// DOFs of the boundary edges are free (angle formulations) or the boundary edge's normal is the
// face's own ("average"), so no moment is transmitted there. Clamped: a ring of ghost faces
// outside the plate (see ghost_thickness), their vertices and the plate's boundary vertices
// fixed. QoI: w_c D / (q a^4) at the centre vertex (n even).
template <class SFF>
static int plate(int n, bool clamped) {
    const double a = 1.0, thick = 0.01, young = 1e7, poisson = 0.3, load = 1e-4;
    const double D = young * thick * thick * thick / (12.0 * (1.0 - poisson * poisson));
    const double exact = clamped ? 0.001265319 : 0.0040623527;
    auto t0 = Clock::now();
    const double h = a / n;
    const int ring = clamped ? 1 : 0, m = n + 2 * ring;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    grid(m, m, -ring * h, -ring * h, h, h, V, F);
    std::vector<bool> ghost(F.rows(), false);
    std::vector<double> th(F.rows(), thick);
    for (int f = 0; f < F.rows(); f++) {
        int cell = f / 2, i = cell % m, j = cell / m;
        if (i < ring || j < ring || i >= m - ring || j >= m - ring) {
            ghost[f] = true;
            th[f] = ghost_thickness(thick);
        }
    }
    Problem<SFF> P;
    P.init(V, F, th, young, poisson);
    std::vector<bool> loaded(F.rows());
    for (int f = 0; f < F.rows(); f++) loaded[f] = !ghost[f];
    lumped_z_load(P, F, loaded, load);
    for (int j = 0; j <= m; j++)
        for (int i = 0; i <= m; i++) {
            int v = j * (m + 1) + i;
            bool interior = i > ring && j > ring && i < m - ring && j < m - ring;
            P.freeIndex[3 * v] = P.freeIndex[3 * v + 1] = -1;
            P.freeIndex[3 * v + 2] = interior ? 0 : -1;
        }
    fix_ghost_edges(P, ghost);
    P.number_free();
    double setup = seconds_since(t0);
    auto t1 = Clock::now();
    Eigen::VectorXd q = P.q0;
    SolveStats st = solve(P, q);
    double solveTime = seconds_since(t1);
    int c = (m / 2) * (m + 1) + m / 2;
    double factor = -q[3 * c + 2] * D / (load * a * a * a * a);
    report(clamped ? "plate_clamped" : "plate_simple", std::to_string(n) + "x" + std::to_string(n), P.nv, P.nfree,
           factor, exact, st, setup, solveTime);
    return st.ok ? 0 : 1;
}

// Scaling check: a flat grid rolled onto a cylinder of radius R (curvature 1/R across x). The
// bending energy per area of an interior face should be D/2 (1/R)^2 with D = E t^3 / 12 (nu = 0)
// if libshell's discrete second fundamental form is the continuum one (checked with the
// "average" formulation, whose normals need no edge DOFs).
static int check() {
    using SFF = LibShell::MidedgeAverageFormulation;
    const int nx = 64, ny = 8;
    const double t = 1e-3, young = 1e6, R = 1.0, L = 1.0;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    grid(nx, ny, 0, 0, L / nx, 0.2 / ny, V, F);
    Problem<SFF> P;
    P.init(V, F, std::vector<double>(F.rows(), t), young, 0.0);
    Eigen::MatrixXd pos = V;
    for (int k = 0; k < V.rows(); k++) {
        double s = V(k, 0);
        pos(k, 0) = R * std::sin(s / R);
        pos(k, 2) = R * (1 - std::cos(s / R));
    }
    int f = 2 * ((ny / 2) * nx + nx / 2);  // an interior face
    Eigen::VectorXd none;
    double e = P.mat.bendingEnergy(P.mesh, pos, none, P.rs, f, nullptr, nullptr);
    double dens = e / P.face_area(f), expect = 0.5 * young * t * t * t / 12.0 / (R * R);
    std::printf("check,bending energy density / (D/2 k^2) = %.6f (1 = continuum scaling)\n", dens / expect);
    return std::abs(dens / expect - 1) < 0.05 ? 0 : 1;
}

template <class SFF>
static int run(char** argv) {
    if (!std::strcmp(argv[1], "cantilever")) return cantilever<SFF>(std::atoi(argv[2]), std::atoi(argv[3]));
    return plate<SFF>(std::atoi(argv[2]), !std::strcmp(argv[3], "clamped"));
}

int main(int argc, char** argv) {
    if (argc >= 2 && !std::strcmp(argv[1], "check")) return check();
    bool ok = argc >= 4 && (!std::strcmp(argv[1], "cantilever") || !std::strcmp(argv[1], "plate"));
    for (int i = 4; ok && i < argc; i++) {
        std::string a = argv[i];
        if (a == "-v") g_opt.verbose = true;
        else if (a == "--rtol" && i + 1 < argc) g_opt.rtol = std::atof(argv[++i]);
        else if (a == "--steps" && i + 1 < argc) g_opt.steps = std::atoi(argv[++i]);
        else if (a == "--maxit" && i + 1 < argc) g_opt.maxit = std::atoi(argv[++i]);
        else if (a == "--full-steps" && i + 1 < argc) g_opt.fullStepIterations = std::atoi(argv[++i]);
        else if (a == "--sff" && i + 1 < argc) g_opt.sff = argv[++i];
        else if (a == "--ghost-stiffness" && i + 1 < argc) g_opt.ghostStiffness = std::atof(argv[++i]);
        else if (a == "--pattern" && i + 1 < argc) g_uniformDiagonals = std::string(argv[++i]) == "uniform";
        else ok = false;
    }
    if (ok && g_opt.sff == "tan") return run<LibShell::MidedgeAngleTanFormulation>(argv);
    if (ok && g_opt.sff == "sin") return run<LibShell::MidedgeAngleSinFormulation>(argv);
    if (ok && g_opt.sff == "average") return run<LibShell::MidedgeAverageFormulation>(argv);
    std::fprintf(stderr,
                 "usage: %s cantilever NX NY [options] | plate N simple|clamped [options] | check\n"
                 "options: --sff tan|sin|average (default tan) --rtol R (1e-10) --ghost-stiffness S (1e6)\n"
                 "         --full-steps N (25; 0: none) --maxit N (60) --steps K (0: adaptive)\n"
                 "         --pattern alternate|uniform (alternate) -v\n",
                 argv[0]);
    return 2;
}

/* Built-in grammars: classic plants and trees from "The Algorithmic Beauty of Plants"
 * (Prusinkiewicz & Lindenmayer 1990, figure numbers in the names; the trees of chapter 2 with
 * leaves the book does not draw) and the leafy grammar of Fayçal & Babahenini. Units are the
 * books' (unit steps); #width sets the tip diameter the pipe rule starts from. Written in
 * xylem's grammar language (docs/lsystem.md). */
#include <string.h>

#include "lsys_internal.h"

/* The trees' leaves: a fan at the end of each apex's branch, a leaf along the branch first and
 * its side leaves rolled around it. The first leaf becomes a cut one step later ("L(s) -> %"),
 * which erases the fan as the apex grows on, so the derived string holds only the youngest fans
 * and the tree's nodes are the book's (tests/test_grammar.c compares them with the bare
 * grammars in tests/data/grammars). */
#define FAN5 "L(ls)[&(la)$L(ls)]/(90)[&(la)$L(ls)]/(90)[&(la)$L(ls)]/(90)[&(la)$L(ls)]"
#define FAN7 "L(ls)[&(la)$L(ls)]/(60)[&(la)$L(ls)]/(60)[&(la)$L(ls)]/(60)[&(la)$L(ls)]" \
             "/(60)[&(la)$L(ls)]/(60)[&(la)$L(ls)]"
#define LEAF_FAN_NOTE                                                                         \
    "// Each apex's branch ends in a fan of leaves, blades rolled flat ($). The last\n"       \
    "// production turns a fan's first leaf into a cut one step later, which sheds the fan\n" \
    "// as the apex grows on: only the youngest twigs keep leaves, and no leaf adds, moves\n" \
    "// or thickens a node.\n"

typedef struct preset {
    const char *name;
    const char *summary;
    const char *source;
} preset;

static const preset presets[] = {
    {"abop-1.24a", "bracketed plant, edge rewriting: F -> F[+F]F[-F]F, 25.7 deg, n = 5",
     "#angle 25.7\n#depth 5\n#width 0.3\n"
     "axiom: F\n"
     "F -> F[+F]F[-F]F\n"},
    {"abop-1.24b", "bracketed plant: F -> F[+F]F[-F][F], 20 deg, n = 5",
     "#angle 20\n#depth 5\n#width 0.3\n"
     "axiom: F\n"
     "F -> F[+F]F[-F][F]\n"},
    {"abop-1.24c", "bushy bracketed plant: F -> FF-[-F+F+F]+[+F-F-F], 22.5 deg, n = 4",
     "#angle 22.5\n#depth 4\n#width 0.3\n"
     "axiom: F\n"
     "F -> FF-[-F+F+F]+[+F-F-F]\n"},
    {"abop-1.24d", "node rewriting: X -> F[+X]F[-X]+X, F -> FF, 20 deg, n = 7",
     "#angle 20\n#depth 7\n#width 0.3\n"
     "axiom: X\n"
     "X -> F[+X]F[-X]+X\n"
     "F -> FF\n"},
    {"abop-1.24e", "node rewriting: X -> F[+X][-X]FX, F -> FF, 25.7 deg, n = 7",
     "#angle 25.7\n#depth 7\n#width 0.3\n"
     "axiom: X\n"
     "X -> F[+X][-X]FX\n"
     "F -> FF\n"},
    {"abop-1.24f", "node rewriting: X -> F-[[X]+X]+F[+FX]-X, F -> FF, 22.5 deg, n = 5",
     "#angle 22.5\n#depth 5\n#width 0.3\n"
     "axiom: X\n"
     "X -> F-[[X]+X]+F[+FX]-X\n"
     "F -> FF\n"},
    {"abop-1.25-bush", "3D bush with leaves (polygon leaves replaced by leaf attachments), n = 7",
     "#angle 22.5\n#depth 7\n#width 0.15\n"
     "axiom: A\n"
     "A -> [&FL!A]/////'[&FL!A]///////'[&FL!A]\n"
     "F -> S/////F\n"
     "S -> FL\n"},
    {"abop-1.28-stochastic", "stochastic bracketed plant: three weighted successors of F, n = 5",
     "#angle 25.7\n#depth 5\n#width 0.3\n#seed 1\n"
     "axiom: F\n"
     "F -> (0.33) F[+F]F[-F]F\n"
     "F -> (0.33) F[+F]F\n"
     "F -> (0.34) F[-F]F\n"},
    {"abop-1.31a", "context-sensitive plant: signals in a string of 0s and 1s, n = 30",
     "#angle 22.5\n#depth 30\n#width 0.3\n"
     "#ignore + - F\n"
     "axiom: F1F1F1\n"
     "p1: 0 < 0 > 0 -> 0\n"
     "p2: 0 < 0 > 1 -> 1[+F1F1]\n"
     "p3: 0 < 1 > 0 -> 1\n"
     "p4: 0 < 1 > 1 -> 1\n"
     "p5: 1 < 0 > 0 -> 0\n"
     "p6: 1 < 0 > 1 -> 1F1\n"
     "p7: 1 < 1 > 0 -> 0\n"
     "p8: 1 < 1 > 1 -> 0\n"
     "p9: + -> -\n"
     "p10: - -> +\n"},
    {"abop-2.6-monopodial",
     "monopodial tree (Honda): trunk with lateral axes, 137.5 deg phyllotaxis, leaves in fans of 5",
     "#define r1 0.9   // contraction ratio, trunk\n"
     "#define r2 0.6   // contraction ratio, branches\n"
     "#define a0 45    // branching angle from the trunk\n"
     "#define a2 45    // branching angle of lateral axes\n"
     "#define d 137.5  // divergence angle\n"
     "#define wr 0.707 // width decrease rate\n"
     "#define ls 0.25  // leaf length\n"
     "#define la 50    // angle of a fan's side leaves to their axis\n"
     "#depth 10\n#width 0.05\n"
     LEAF_FAN_NOTE
     "axiom: A(1,0.6)\n"
     "p1: A(l,w) : * -> !(w)F(l)[&(a0)B(l*r2,w*wr) " FAN5 "]/(d)A(l*r1,w*wr) " FAN5 "\n"
     "p2: B(l,w) : * -> !(w)F(l)[-(a2)$C(l*r2,w*wr) " FAN5 "]C(l*r1,w*wr) " FAN5 "\n"
     "p3: C(l,w) : * -> !(w)F(l)[+(a2)$B(l*r2,w*wr) " FAN5 "]B(l*r1,w*wr) " FAN5 "\n"
     "p4: L(s) : * -> %\n"},
    {"abop-2.7-sympodial",
     "sympodial tree (Aono & Kunii): every apex forks in two, leaves in fans of 5, n = 10",
     "#define r1 0.9\n#define r2 0.7\n#define a1 10\n#define a2 60\n#define wr 0.707\n"
     "#define ls 0.3   // leaf length\n"
     "#define la 50    // angle of a fan's side leaves to their axis\n"
     "#depth 10\n#width 0.05\n"
     LEAF_FAN_NOTE
     "axiom: A(1,0.6)\n"
     "p1: A(l,w) : * -> !(w)F(l)[&(a1)B(l*r1,w*wr) " FAN5 "]/(180)[&(a2)B(l*r2,w*wr) " FAN5 "]\n"
     "p2: B(l,w) : * -> !(w)F(l)[+(a1)$B(l*r1,w*wr) " FAN5 "][-(a2)$B(l*r2,w*wr) " FAN5 "]\n"
     "p3: L(s) : * -> %\n"},
    {"abop-2.8-ternary",
     "ternary tree with gravitropism (ABOP 2.8a): three-way forks, leaves in fans of 7, n = 6",
     "#define d1 94.74  // divergence angle 1\n"
     "#define d2 132.63 // divergence angle 2\n"
     "#define a 18.95   // branching angle\n"
     "#define lr 1.109  // elongation rate\n"
     "#define vr 1.732  // width increase rate\n"
     "#define ls 40     // leaf length\n"
     "#define la 55     // angle of a fan's side leaves to their twig\n"
     "#tropism 0 -1 0 0.22\n"
     "#depth 6\n#width 2\n"
     LEAF_FAN_NOTE
     "axiom: !(1)F(200)/(45)A\n"
     "p1: A : * -> !(vr)F(50)[&(a)F(50)A " FAN7 "]/(d1)[&(a)F(50)A " FAN7 "]/(d2)[&(a)F(50)A "
     FAN7 "]\n"
     "p2: F(l) : * -> F(l*lr)\n"
     "p3: !(w) : * -> !(w*vr)\n"
     "p4: L(s) : * -> %\n"},
    {"faycal-leaves", "Fayçal & Babahenini's leafy grammar F[+FL][FL-][>FL] ('>' written '/')",
     "#angle 30\n#depth 4\n#width 0.08\n#step 1\n"
     "axiom: F\n"
     "F -> F[+FL][FL-][/FL]\n"},
};

#define PRESET_COUNT (sizeof presets / sizeof presets[0])

size_t xyl_lsystem_preset_count(void)
{
    return PRESET_COUNT;
}

const char *xyl_lsystem_preset_name(size_t index)
{
    return index < PRESET_COUNT ? presets[index].name : NULL;
}

const char *xyl_lsystem_preset_summary(size_t index)
{
    return index < PRESET_COUNT ? presets[index].summary : NULL;
}

const char *xyl_lsystem_preset_source(const char *name)
{
    if (!name) return NULL;
    for (size_t i = 0; i < PRESET_COUNT; ++i)
        if (strcmp(presets[i].name, name) == 0) return presets[i].source;
    return NULL;
}

const char *xyl_lsystem_default_preset(void)
{
    return "abop-2.8-ternary";
}

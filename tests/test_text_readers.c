/* The text readers (.skel and OBJ leaf meshes) share one line and token reader in core. These
 * cases pin what each reader reports for malformed input: the result code, the line, column and
 * index in the diag, and the message, byte for byte. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "xylem/xyl_foliage.h"
#include "xylem/xyl_skeleton.h"

typedef struct bad_case {
    const char *text;
    xyl_result code;
    uint32_t line, column;
    int64_t index;
    const char *message;
} bad_case;

static const bad_case skel_cases[] = {
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0\nend\n",
     XYL_ERR_PARSE, 4, 13, 0, "the line ends where the node radius was expected"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1 extra\nend\n",
     XYL_ERR_PARSE, 4, 16, 0, "unexpected 'extra' after the end of the record"},
    {"xylem-skeleton 1\r\nnodes 1\r\nleaves 0\r\nn 0 -1 1.5e 0 0 1\r\nend\r\n",
     XYL_ERR_PARSE, 4, 8, 0, "the node position x '1.5e' is not a number"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 nan 0 1\nend\n",
     XYL_ERR_NON_FINITE, 4, 10, 0, "the node position y is 'nan'; numbers must be finite"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 -NaN(0x1) 0 1\nend\n",
     XYL_ERR_NON_FINITE, 4, 10, 0, "the node position y is '-NaN(0x1)'; numbers must be finite"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 3.5e38 1\nend\n",
     XYL_ERR_NON_FINITE, 4, 12, 0, "the node position z '3.5e38' is too large for a float"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1e99999999999999999999\nend\n",
     XYL_ERR_NON_FINITE, 4, 14, 0, "the node radius '1e99999999999999999999' is too large for a float"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\n  n 0 x 0 0 0 1 # c\nend\n",
     XYL_ERR_PARSE, 4, 7, 0, "the parent id 'x' is not an integer"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1\t#\tc\n\t  n 1\nend\n",
     XYL_ERR_PARSE, 5, 4, -1, "more node records than the 1 announced"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 7 -1 0 0 0 1\nend\n",
     XYL_ERR_PARSE, 4, 3, 0, "node id 7 is out of order: ids count 0, 1, 2, ... so 0 belongs here"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1\n#\n\nbogus\xff\x01token-that-is-far-too-long-to-show\n",
     XYL_ERR_PARSE, 7, 1, -1, "unknown record 'bogus??token-that-is-far...'; expected 'n', 'l' or 'end'"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 1",
     XYL_ERR_TRUNCATED, 4, 15, -1, "the text ends without 'end' (1 of 1 nodes, 0 of 0 leaves read)"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 .e5 1\nend\n",
     XYL_ERR_PARSE, 4, 12, 0, "the node position z '.e5' is not a number"},
    {"xylem-skeleton 1\nnodes 1\nleaves 0\nn 0 -1 0 0 0 -0.0\nend\n",
     XYL_ERR_INVALID_SKELETON, 4, 14, 0, "node 0 has radius -0; radii must be > 0"},
    {"xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\nl 0 0 0 x 0 0 1 1 0 0 0 1 0 1\nend\n",
     XYL_ERR_PARSE, 5, 9, 0, "the leaf position z 'x' is not a number"},
    {"xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\nl 0 0 0 0 0 0 y 1 0 0 0 1 0 1\nend\n",
     XYL_ERR_PARSE, 5, 15, 0, "the leaf heading z 'y' is not a number"},
    {"xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\nl 0 0 0 0 0 0 1 inf 0 0 0 1 0 1\nend\n",
     XYL_ERR_NON_FINITE, 5, 17, 0, "the leaf left vector x is 'inf'; numbers must be finite"},
    {"xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\nl 0 0 0 0 0 0 1 1 0 0 0 1e39 0 1\nend\n",
     XYL_ERR_NON_FINITE, 5, 25, 0, "the leaf up vector y '1e39' is too large for a float"},
    {"xylem-skeleton 1\nnodes 1\nleaves 1\nn 0 -1 0 0 0 1\nl 0 0 0 0 0 0 1 1 0 0 0 1 0\nend\n",
     XYL_ERR_PARSE, 5, 28, 0, "the line ends where the leaf size was expected"},
};

static const bad_case obj_cases[] = {
    {"v 0 0 0\nv 1 0 0\nv 0 1\n",
     XYL_ERR_PARSE, 3, 6, -1, "the line ends where z was expected"},
    {"v 0 0 0\nv 1 0 0\nv 0 1",
     XYL_ERR_TRUNCATED, 3, 6, -1, "the text ends inside a record: z expected"},
    {"v 0 0 0\r\nv 1 0 0\r\nv 0 1 1.5e\r\nf 1 2 3\r\n",
     XYL_ERR_PARSE, 3, 7, -1, "'1.5e' is not a number"},
    {"v 0 0 0\nv 1 0 inf\n",
     XYL_ERR_NON_FINITE, 2, 7, -1, "vertex coordinate 'inf' is not finite"},
    {"v 0 0 0\nv 1 0 NaN(1)\n",
     XYL_ERR_PARSE, 2, 7, -1, "'NaN(1)' is not a number"},
    {"v 0 0 0\nv 1 0 1e999\n",
     XYL_ERR_LIMIT_EXCEEDED, 2, 7, -1, "vertex z '1e999' is beyond limits.max_coordinate (1e+06)"},
    {"v 0 0 0\nv 1 0 0 1 2 3 4 5\n",
     XYL_ERR_PARSE, 2, 17, -1, "a vertex has at most 7 numbers (x y z [w], or x y z r g b [a])"},
    {"v 0 0 0\nv 1 0 0 1 2\n",
     XYL_ERR_PARSE, 2, 12, -1, "a vertex with 5 numbers: x y z [w], or x y z r g b [a]"},
    {"v 0 0 0 # c\nv 1 0 0\nv 0 1 0\n\t f 1 2 0\n",
     XYL_ERR_PARSE, 4, 9, -1, "face corner '0' has no vertex index (indices count from 1)"},
    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
     XYL_ERR_PARSE, 4, 7, -1, "face corner '9' names a vertex that does not exist (3 defined so far)"},
    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n",
     XYL_ERR_PARSE, 4, 7, -1, "face corner '3/x' is not i, i/t, i//n or i/t/n (indices non-zero)"},
    {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \x01\xfe-a-very-long-face-corner-token\n",
     XYL_ERR_PARSE, 4, 7, -1, "face corner '?" "?-a-very-long-face-...' has no vertex index (indices count from 1)"},
    {"v 0 0 0\nbogus\n",
     XYL_ERR_PARSE, 2, 1, -1, "unknown record 'bogus'"},
    {"v . 0 0\n",
     XYL_ERR_PARSE, 1, 3, -1, "'.' is not a number"},
};

static void check_diag(size_t i, const bad_case *c, xyl_result r, const xyl_diag *d)
{
    if (r != c->code || d->code != c->code || d->line != c->line || d->column != c->column ||
        d->index != c->index || strcmp(d->message, c->message) != 0)
        fail_msg("case %zu: got %s at %u:%u index %lld \"%s\"; want %s at %u:%u index %lld \"%s\"",
                 i, xyl_result_string(r), d->line, d->column, (long long)d->index, d->message,
                 xyl_result_string(c->code), c->line, c->column, (long long)c->index, c->message);
}

static void skel_reader_reports_bad_input_exactly(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof skel_cases / sizeof *skel_cases; ++i) {
        xyl_diag d = {0};
        xyl_skeleton *sk = NULL;
        const char *t = skel_cases[i].text;
        xyl_result r = xyl_skeleton_read_text(t, strlen(t), NULL, &sk, &d);
        assert_null(sk);
        check_diag(i, &skel_cases[i], r, &d);
    }
}

static void obj_reader_reports_bad_input_exactly(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof obj_cases / sizeof *obj_cases; ++i) {
        xyl_diag d = {0};
        size_t n = 99;
        const char *t = obj_cases[i].text;
        xyl_result r = xyl_foliage_leaves_from_obj(t, strlen(t), NULL, NULL, 0, &n, &d);
        assert_int_equal(n, 99);
        check_diag(i, &obj_cases[i], r, &d);
    }
}

static uint32_t bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Numbers at the float range's ends and ones that are not exact in binary come back as the
 * nearest float, sign of zero included. */
static void skel_reader_rounds_numbers_to_the_nearest_float(void **state)
{
    (void)state;
    const char *t = "xylem-skeleton 1\nnodes 2\nleaves 0\n"
                    "n 0 -1 1e-45 3.4028235e38 -0.0 0.1\n"
                    "n 1 0 +.5e1 -1.17549435E-38 16777217 340282346638528859811704183484516925440\n"
                    "end\n";
    const float want[2][4] = {{1e-45f, 3.4028235e38f, -0.0f, 0.1f},
                              {5.0f, -1.17549435e-38f, 16777216.0f, 3.40282347e38f}};
    xyl_diag d = {0};
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_read_text(t, strlen(t), NULL, &sk, &d), XYL_OK);
    assert_int_equal(sk->node_count, 2);
    for (size_t i = 0; i < 2; ++i) {
        const xyl_skel_node *n = &sk->nodes[i];
        assert_int_equal(bits(n->pos.x), bits(want[i][0]));
        assert_int_equal(bits(n->pos.y), bits(want[i][1]));
        assert_int_equal(bits(n->pos.z), bits(want[i][2]));
        assert_int_equal(bits(n->radius), bits(want[i][3]));
    }
    xyl_skeleton_destroy(sk);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(skel_reader_reports_bad_input_exactly),
        cmocka_unit_test(obj_reader_reports_bad_input_exactly),
        cmocka_unit_test(skel_reader_rounds_numbers_to_the_nearest_float),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* Noise tables, built once at start-up with libm; look-ups in dist_impl.h. */
#include <math.h>

#include "dist_impl.h"

#define DEFAULT_FLOOR_DEPTH 30.0
#define GAMMA_TOP_TAIL 1e-9 /* the Gamma's log-density grid ends at this tail */

/* 2^(-j/512): literals cast so the float build takes them as they are */
#define R(x) ((hstpf_real_t)(x))
const hstpf_real_t hstpf__exp2_tab[HSTPF__EXP_N + 1] = {
    R(1.000000000e+00), R(9.986471129e-01), R(9.972960561e-01), R(9.959468271e-01),
    R(9.945994235e-01), R(9.932538427e-01), R(9.919100824e-01), R(9.905681401e-01),
    R(9.892280132e-01), R(9.878896994e-01), R(9.865531961e-01), R(9.852185010e-01),
    R(9.838856116e-01), R(9.825545255e-01), R(9.812252401e-01), R(9.798977531e-01),
    R(9.785720621e-01), R(9.772481646e-01), R(9.759260581e-01), R(9.746057403e-01),
    R(9.732872088e-01), R(9.719704611e-01), R(9.706554948e-01), R(9.693423075e-01),
    R(9.680308967e-01), R(9.667212602e-01), R(9.654133955e-01), R(9.641073002e-01),
    R(9.628029718e-01), R(9.615004081e-01), R(9.601996066e-01), R(9.589005649e-01),
    R(9.576032807e-01), R(9.563077516e-01), R(9.550139751e-01), R(9.537219490e-01),
    R(9.524316709e-01), R(9.511431384e-01), R(9.498563491e-01), R(9.485713007e-01),
    R(9.472879908e-01), R(9.460064171e-01), R(9.447265772e-01), R(9.434484688e-01),
    R(9.421720895e-01), R(9.408974370e-01), R(9.396245090e-01), R(9.383533031e-01),
    R(9.370838171e-01), R(9.358160484e-01), R(9.345499950e-01), R(9.332856543e-01),
    R(9.320230242e-01), R(9.307621023e-01), R(9.295028862e-01), R(9.282453737e-01),
    R(9.269895625e-01), R(9.257354503e-01), R(9.244830348e-01), R(9.232323136e-01),
    R(9.219832845e-01), R(9.207359452e-01), R(9.194902934e-01), R(9.182463268e-01),
    R(9.170040432e-01), R(9.157634403e-01), R(9.145245157e-01), R(9.132872673e-01),
    R(9.120516927e-01), R(9.108177897e-01), R(9.095855561e-01), R(9.083549895e-01),
    R(9.071260878e-01), R(9.058988486e-01), R(9.046732697e-01), R(9.034493489e-01),
    R(9.022270839e-01), R(9.010064725e-01), R(8.997875125e-01), R(8.985702015e-01),
    R(8.973545375e-01), R(8.961405181e-01), R(8.949281412e-01), R(8.937174044e-01),
    R(8.925083057e-01), R(8.913008427e-01), R(8.900950133e-01), R(8.888908152e-01),
    R(8.876882463e-01), R(8.864873043e-01), R(8.852879870e-01), R(8.840902923e-01),
    R(8.828942180e-01), R(8.816997618e-01), R(8.805069215e-01), R(8.793156951e-01),
    R(8.781260802e-01), R(8.769380747e-01), R(8.757516765e-01), R(8.745668834e-01),
    R(8.733836931e-01), R(8.722021036e-01), R(8.710221126e-01), R(8.698437180e-01),
    R(8.686669176e-01), R(8.674917094e-01), R(8.663180910e-01), R(8.651460604e-01),
    R(8.639756155e-01), R(8.628067540e-01), R(8.616394739e-01), R(8.604737729e-01),
    R(8.593096491e-01), R(8.581471001e-01), R(8.569861240e-01), R(8.558267185e-01),
    R(8.546688816e-01), R(8.535126110e-01), R(8.523579048e-01), R(8.512047608e-01),
    R(8.500531769e-01), R(8.489031509e-01), R(8.477546807e-01), R(8.466077644e-01),
    R(8.454623996e-01), R(8.443185845e-01), R(8.431763167e-01), R(8.420355944e-01),
    R(8.408964153e-01), R(8.397587773e-01), R(8.386226785e-01), R(8.374881167e-01),
    R(8.363550898e-01), R(8.352235958e-01), R(8.340936326e-01), R(8.329651980e-01),
    R(8.318382902e-01), R(8.307129069e-01), R(8.295890461e-01), R(8.284667058e-01),
    R(8.273458838e-01), R(8.262265782e-01), R(8.251087870e-01), R(8.239925079e-01),
    R(8.228777391e-01), R(8.217644784e-01), R(8.206527238e-01), R(8.195424733e-01),
    R(8.184337249e-01), R(8.173264764e-01), R(8.162207260e-01), R(8.151164715e-01),
    R(8.140137109e-01), R(8.129124423e-01), R(8.118126635e-01), R(8.107143726e-01),
    R(8.096175676e-01), R(8.085222464e-01), R(8.074284071e-01), R(8.063360476e-01),
    R(8.052451660e-01), R(8.041557602e-01), R(8.030678282e-01), R(8.019813681e-01),
    R(8.008963778e-01), R(7.998128555e-01), R(7.987307990e-01), R(7.976502064e-01),
    R(7.965710757e-01), R(7.954934049e-01), R(7.944171922e-01), R(7.933424354e-01),
    R(7.922691326e-01), R(7.911972819e-01), R(7.901268813e-01), R(7.890579289e-01),
    R(7.879904226e-01), R(7.869243605e-01), R(7.858597406e-01), R(7.847965611e-01),
    R(7.837348200e-01), R(7.826745152e-01), R(7.816156450e-01), R(7.805582073e-01),
    R(7.795022001e-01), R(7.784476216e-01), R(7.773944699e-01), R(7.763427429e-01),
    R(7.752924388e-01), R(7.742435557e-01), R(7.731960916e-01), R(7.721500445e-01),
    R(7.711054127e-01), R(7.700621941e-01), R(7.690203869e-01), R(7.679799891e-01),
    R(7.669409989e-01), R(7.659034143e-01), R(7.648672335e-01), R(7.638324545e-01),
    R(7.627990754e-01), R(7.617670943e-01), R(7.607365095e-01), R(7.597073188e-01),
    R(7.586795206e-01), R(7.576531129e-01), R(7.566280937e-01), R(7.556044613e-01),
    R(7.545822138e-01), R(7.535613492e-01), R(7.525418658e-01), R(7.515237616e-01),
    R(7.505070348e-01), R(7.494916835e-01), R(7.484777059e-01), R(7.474651000e-01),
    R(7.464538641e-01), R(7.454439963e-01), R(7.444354948e-01), R(7.434283576e-01),
    R(7.424225829e-01), R(7.414181690e-01), R(7.404151139e-01), R(7.394134158e-01),
    R(7.384130730e-01), R(7.374140834e-01), R(7.364164454e-01), R(7.354201571e-01),
    R(7.344252167e-01), R(7.334316223e-01), R(7.324393721e-01), R(7.314484643e-01),
    R(7.304588971e-01), R(7.294706687e-01), R(7.284837772e-01), R(7.274982209e-01),
    R(7.265139979e-01), R(7.255311065e-01), R(7.245495448e-01), R(7.235693111e-01),
    R(7.225904035e-01), R(7.216128202e-01), R(7.206365596e-01), R(7.196616197e-01),
    R(7.186879987e-01), R(7.177156950e-01), R(7.167447067e-01), R(7.157750320e-01),
    R(7.148066692e-01), R(7.138396165e-01), R(7.128738721e-01), R(7.119094342e-01),
    R(7.109463011e-01), R(7.099844710e-01), R(7.090239422e-01), R(7.080647128e-01),
    R(7.071067812e-01), R(7.061501455e-01), R(7.051948041e-01), R(7.042407551e-01),
    R(7.032879969e-01), R(7.023365276e-01), R(7.013863456e-01), R(7.004374491e-01),
    R(6.994898363e-01), R(6.985435055e-01), R(6.975984550e-01), R(6.966546830e-01),
    R(6.957121879e-01), R(6.947709678e-01), R(6.938310211e-01), R(6.928923461e-01),
    R(6.919549410e-01), R(6.910188041e-01), R(6.900839336e-01), R(6.891503280e-01),
    R(6.882179854e-01), R(6.872869041e-01), R(6.863570825e-01), R(6.854285189e-01),
    R(6.845012115e-01), R(6.835751586e-01), R(6.826503586e-01), R(6.817268097e-01),
    R(6.808045103e-01), R(6.798834587e-01), R(6.789636531e-01), R(6.780450919e-01),
    R(6.771277735e-01), R(6.762116960e-01), R(6.752968579e-01), R(6.743832575e-01),
    R(6.734708931e-01), R(6.725597630e-01), R(6.716498656e-01), R(6.707411991e-01),
    R(6.698337620e-01), R(6.689275526e-01), R(6.680225691e-01), R(6.671188100e-01),
    R(6.662162735e-01), R(6.653149581e-01), R(6.644148621e-01), R(6.635159838e-01),
    R(6.626183216e-01), R(6.617218738e-01), R(6.608266388e-01), R(6.599326150e-01),
    R(6.590398006e-01), R(6.581481942e-01), R(6.572577940e-01), R(6.563685984e-01),
    R(6.554806058e-01), R(6.545938145e-01), R(6.537082230e-01), R(6.528238295e-01),
    R(6.519406326e-01), R(6.510586305e-01), R(6.501778217e-01), R(6.492982045e-01),
    R(6.484197773e-01), R(6.475425386e-01), R(6.466664866e-01), R(6.457916199e-01),
    R(6.449179367e-01), R(6.440454355e-01), R(6.431741148e-01), R(6.423039728e-01),
    R(6.414350080e-01), R(6.405672189e-01), R(6.397006038e-01), R(6.388351611e-01),
    R(6.379708892e-01), R(6.371077866e-01), R(6.362458517e-01), R(6.353850829e-01),
    R(6.345254786e-01), R(6.336670373e-01), R(6.328097573e-01), R(6.319536371e-01),
    R(6.310986752e-01), R(6.302448699e-01), R(6.293922198e-01), R(6.285407232e-01),
    R(6.276903785e-01), R(6.268411843e-01), R(6.259931389e-01), R(6.251462409e-01),
    R(6.243004886e-01), R(6.234558805e-01), R(6.226124151e-01), R(6.217700908e-01),
    R(6.209289060e-01), R(6.200888593e-01), R(6.192499491e-01), R(6.184121738e-01),
    R(6.175755320e-01), R(6.167400220e-01), R(6.159056424e-01), R(6.150723916e-01),
    R(6.142402681e-01), R(6.134092703e-01), R(6.125793968e-01), R(6.117506460e-01),
    R(6.109230165e-01), R(6.100965066e-01), R(6.092711149e-01), R(6.084468399e-01),
    R(6.076236800e-01), R(6.068016337e-01), R(6.059806996e-01), R(6.051608762e-01),
    R(6.043421618e-01), R(6.035245551e-01), R(6.027080545e-01), R(6.018926585e-01),
    R(6.010783657e-01), R(6.002651746e-01), R(5.994530835e-01), R(5.986420912e-01),
    R(5.978321960e-01), R(5.970233965e-01), R(5.962156913e-01), R(5.954090788e-01),
    R(5.946035575e-01), R(5.937991260e-01), R(5.929957828e-01), R(5.921935265e-01),
    R(5.913923555e-01), R(5.905922684e-01), R(5.897932637e-01), R(5.889953400e-01),
    R(5.881984958e-01), R(5.874027297e-01), R(5.866080401e-01), R(5.858144256e-01),
    R(5.850218848e-01), R(5.842304163e-01), R(5.834400185e-01), R(5.826506900e-01),
    R(5.818624294e-01), R(5.810752352e-01), R(5.802891060e-01), R(5.795040404e-01),
    R(5.787200368e-01), R(5.779370939e-01), R(5.771552103e-01), R(5.763743845e-01),
    R(5.755946150e-01), R(5.748159004e-01), R(5.740382394e-01), R(5.732616305e-01),
    R(5.724860722e-01), R(5.717115632e-01), R(5.709381020e-01), R(5.701656872e-01),
    R(5.693943174e-01), R(5.686239911e-01), R(5.678547071e-01), R(5.670864638e-01),
    R(5.663192598e-01), R(5.655530938e-01), R(5.647879643e-01), R(5.640238699e-01),
    R(5.632608093e-01), R(5.624987810e-01), R(5.617377837e-01), R(5.609778159e-01),
    R(5.602188762e-01), R(5.594609633e-01), R(5.587040758e-01), R(5.579482122e-01),
    R(5.571933713e-01), R(5.564395516e-01), R(5.556867517e-01), R(5.549349702e-01),
    R(5.541842059e-01), R(5.534344572e-01), R(5.526857229e-01), R(5.519380015e-01),
    R(5.511912917e-01), R(5.504455921e-01), R(5.497009013e-01), R(5.489572181e-01),
    R(5.482145409e-01), R(5.474728685e-01), R(5.467321995e-01), R(5.459925326e-01),
    R(5.452538663e-01), R(5.445161994e-01), R(5.437795305e-01), R(5.430438581e-01),
    R(5.423091811e-01), R(5.415754980e-01), R(5.408428075e-01), R(5.401111082e-01),
    R(5.393803989e-01), R(5.386506781e-01), R(5.379219445e-01), R(5.371941969e-01),
    R(5.364674338e-01), R(5.357416539e-01), R(5.350168559e-01), R(5.342930385e-01),
    R(5.335702003e-01), R(5.328483401e-01), R(5.321274564e-01), R(5.314075481e-01),
    R(5.306886136e-01), R(5.299706519e-01), R(5.292536614e-01), R(5.285376409e-01),
    R(5.278225892e-01), R(5.271085048e-01), R(5.263953865e-01), R(5.256832330e-01),
    R(5.249720429e-01), R(5.242618150e-01), R(5.235525479e-01), R(5.228442404e-01),
    R(5.221368912e-01), R(5.214304989e-01), R(5.207250623e-01), R(5.200205801e-01),
    R(5.193170510e-01), R(5.186144736e-01), R(5.179128468e-01), R(5.172121692e-01),
    R(5.165124395e-01), R(5.158136565e-01), R(5.151158188e-01), R(5.144189253e-01),
    R(5.137229746e-01), R(5.130279654e-01), R(5.123338964e-01), R(5.116407665e-01),
    R(5.109485743e-01), R(5.102573186e-01), R(5.095669980e-01), R(5.088776114e-01),
    R(5.081891575e-01), R(5.075016349e-01), R(5.068150425e-01), R(5.061293789e-01),
    R(5.054446430e-01), R(5.047608335e-01), R(5.040779491e-01), R(5.033959885e-01),
    R(5.027149506e-01), R(5.020348340e-01), R(5.013556375e-01), R(5.006773599e-01),
    R(5.000000000e-01),
};
/* log2(1 + j/256) */
const hstpf_real_t hstpf__log2_tab[HSTPF__LOG_N + 1] = {
    R(0.000000000e+00), R(5.624549194e-03), R(1.122725542e-02), R(1.680828769e-02),
    R(2.236781303e-02), R(2.790599657e-02), R(3.342300154e-02), R(3.891898929e-02),
    R(4.439411936e-02), R(4.984854945e-02), R(5.528243550e-02), R(6.069593169e-02),
    R(6.608919046e-02), R(7.146236256e-02), R(7.681559705e-02), R(8.214904135e-02),
    R(8.746284125e-02), R(9.275714092e-02), R(9.803208296e-02), R(1.032878084e-01),
    R(1.085244568e-01), R(1.137421660e-01), R(1.189410727e-01), R(1.241213118e-01),
    R(1.292830169e-01), R(1.344263202e-01), R(1.395513524e-01), R(1.446582428e-01),
    R(1.497471195e-01), R(1.548181091e-01), R(1.598713368e-01), R(1.649069267e-01),
    R(1.699250014e-01), R(1.749256825e-01), R(1.799090900e-01), R(1.848753429e-01),
    R(1.898245589e-01), R(1.947568544e-01), R(1.996723448e-01), R(2.045711442e-01),
    R(2.094533656e-01), R(2.143191208e-01), R(2.191685205e-01), R(2.240016742e-01),
    R(2.288186905e-01), R(2.336196768e-01), R(2.384047393e-01), R(2.431739835e-01),
    R(2.479275134e-01), R(2.526654325e-01), R(2.573878427e-01), R(2.620948454e-01),
    R(2.667865407e-01), R(2.714630279e-01), R(2.761244053e-01), R(2.807707701e-01),
    R(2.854022189e-01), R(2.900188469e-01), R(2.946207489e-01), R(2.992080184e-01),
    R(3.037807482e-01), R(3.083390301e-01), R(3.128829553e-01), R(3.174126138e-01),
    R(3.219280949e-01), R(3.264294871e-01), R(3.309168781e-01), R(3.353903547e-01),
    R(3.398500029e-01), R(3.442959079e-01), R(3.487281542e-01), R(3.531468255e-01),
    R(3.575520046e-01), R(3.619437737e-01), R(3.663222142e-01), R(3.706874068e-01),
    R(3.750394313e-01), R(3.793783671e-01), R(3.837042925e-01), R(3.880172853e-01),
    R(3.923174228e-01), R(3.966047812e-01), R(4.008794363e-01), R(4.051414631e-01),
    R(4.093909361e-01), R(4.136279290e-01), R(4.178525149e-01), R(4.220647662e-01),
    R(4.262647547e-01), R(4.304525517e-01), R(4.346282276e-01), R(4.387918526e-01),
    R(4.429434958e-01), R(4.470832262e-01), R(4.512111118e-01), R(4.553272203e-01),
    R(4.594316186e-01), R(4.635243733e-01), R(4.676055501e-01), R(4.716752144e-01),
    R(4.757334310e-01), R(4.797802640e-01), R(4.838157773e-01), R(4.878400338e-01),
    R(4.918530963e-01), R(4.958550269e-01), R(4.998458871e-01), R(5.038257380e-01),
    R(5.077946402e-01), R(5.117526538e-01), R(5.156998383e-01), R(5.196362528e-01),
    R(5.235619561e-01), R(5.274770061e-01), R(5.313814605e-01), R(5.352753766e-01),
    R(5.391588111e-01), R(5.430318203e-01), R(5.468944599e-01), R(5.507467854e-01),
    R(5.545888517e-01), R(5.584207133e-01), R(5.622424242e-01), R(5.660540382e-01),
    R(5.698556083e-01), R(5.736471875e-01), R(5.774288280e-01), R(5.812005819e-01),
    R(5.849625007e-01), R(5.887146356e-01), R(5.924570373e-01), R(5.961897561e-01),
    R(5.999128422e-01), R(6.036263450e-01), R(6.073303137e-01), R(6.110247973e-01),
    R(6.147098441e-01), R(6.183855023e-01), R(6.220518195e-01), R(6.257088431e-01),
    R(6.293566201e-01), R(6.329951971e-01), R(6.366246205e-01), R(6.402449362e-01),
    R(6.438561898e-01), R(6.474584265e-01), R(6.510516912e-01), R(6.546360285e-01),
    R(6.582114828e-01), R(6.617780978e-01), R(6.653359172e-01), R(6.688849843e-01),
    R(6.724253420e-01), R(6.759570329e-01), R(6.794800995e-01), R(6.829945837e-01),
    R(6.865005272e-01), R(6.899979714e-01), R(6.934869575e-01), R(6.969675262e-01),
    R(7.004397181e-01), R(7.039035734e-01), R(7.073591321e-01), R(7.108064337e-01),
    R(7.142455177e-01), R(7.176764231e-01), R(7.210991887e-01), R(7.245138531e-01),
    R(7.279204546e-01), R(7.313190310e-01), R(7.347096202e-01), R(7.380922596e-01),
    R(7.414669864e-01), R(7.448338375e-01), R(7.481928496e-01), R(7.515440591e-01),
    R(7.548875022e-01), R(7.582232147e-01), R(7.615512324e-01), R(7.648715907e-01),
    R(7.681843248e-01), R(7.714894695e-01), R(7.747870596e-01), R(7.780771295e-01),
    R(7.813597135e-01), R(7.846348456e-01), R(7.879025594e-01), R(7.911628886e-01),
    R(7.944158664e-01), R(7.976615259e-01), R(8.008998999e-01), R(8.041310212e-01),
    R(8.073549221e-01), R(8.105716347e-01), R(8.137811912e-01), R(8.169836233e-01),
    R(8.201789624e-01), R(8.233672400e-01), R(8.265484873e-01), R(8.297227351e-01),
    R(8.328900142e-01), R(8.360503551e-01), R(8.392037881e-01), R(8.423503434e-01),
    R(8.454900509e-01), R(8.486229404e-01), R(8.517490414e-01), R(8.548683833e-01),
    R(8.579809951e-01), R(8.610869060e-01), R(8.641861447e-01), R(8.672787397e-01),
    R(8.703647196e-01), R(8.734441125e-01), R(8.765169466e-01), R(8.795832496e-01),
    R(8.826430494e-01), R(8.856963733e-01), R(8.887432489e-01), R(8.917837032e-01),
    R(8.948177633e-01), R(8.978454560e-01), R(9.008668080e-01), R(9.038818457e-01),
    R(9.068905956e-01), R(9.098930838e-01), R(9.128893362e-01), R(9.158793788e-01),
    R(9.188632373e-01), R(9.218409371e-01), R(9.248125036e-01), R(9.277779621e-01),
    R(9.307373376e-01), R(9.336906550e-01), R(9.366379390e-01), R(9.395792143e-01),
    R(9.425145053e-01), R(9.454438364e-01), R(9.483672316e-01), R(9.512847150e-01),
    R(9.541963104e-01), R(9.571020416e-01), R(9.600019321e-01), R(9.628960053e-01),
    R(9.657842847e-01), R(9.686667932e-01), R(9.715435540e-01), R(9.744145898e-01),
    R(9.772799235e-01), R(9.801395776e-01), R(9.829935747e-01), R(9.858419370e-01),
    R(9.886846868e-01), R(9.915218461e-01), R(9.943534369e-01), R(9.971794809e-01),
    R(1.000000000e+00),
};
#undef R

/* ---- exact distribution functions (double, init time only) ---------- */

/* Regularised incomplete gamma: *p = P(k, x), *q = Q(k, x) = 1 - P. Series
 * below k + 1, Lentz continued fraction above, so each tail keeps its
 * relative precision. */
static void gamma_pq(double k, double x, double *p, double *q)
{
    const double tiny = 1e-300;
    double lead;
    int n;
    if (x <= 0.0) {
        *p = 0.0;
        *q = 1.0;
        return;
    }
    lead = exp(k * log(x) - x - lgamma(k));
    if (x < k + 1.0) {
        double ap = k, term = 1.0 / k, sum = term;
        for (n = 0; n < 10000; ++n) {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if (term < sum * 1e-17) {
                break;
            }
        }
        *p = sum * lead;
        *q = 1.0 - *p;
    } else {
        double b = x + 1.0 - k, c = 1.0 / tiny, d = 1.0 / b, h = d;
        for (n = 1; n < 10000; ++n) {
            const double an = -(double)n * ((double)n - k);
            double del;
            b += 2.0;
            d = an * d + b;
            if (fabs(d) < tiny) {
                d = tiny;
            }
            c = b + an / c;
            if (fabs(c) < tiny) {
                c = tiny;
            }
            d = 1.0 / d;
            del = d * c;
            h *= del;
            if (fabs(del - 1.0) < 1e-16) {
                break;
            }
        }
        *q = lead * h;
        *p = 1.0 - *q;
    }
}

/* Piecewise-linear table density: CDF at x (normalised by `mass`). */
static double table_cdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    double c = 0.0;
    uint16_t j;
    if (x <= sp->table_x[0]) {
        return 0.0;
    }
    for (j = 0; j + 1u < sp->table_n; ++j) {
        const double x0 = sp->table_x[j], x1 = sp->table_x[j + 1u];
        const double p0 = sp->table_p[j], p1 = sp->table_p[j + 1u];
        if (x < x1) {
            const double d = x - x0;
            c += p0 * d + 0.5 * (p1 - p0) / (x1 - x0) * d * d;
            return c / mass;
        }
        c += 0.5 * (p0 + p1) * (x1 - x0);
    }
    return 1.0;
}

static double table_pdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    uint16_t j;
    if (x < sp->table_x[0] || x > sp->table_x[sp->table_n - 1u]) {
        return 0.0;
    }
    for (j = 0; j + 1u < sp->table_n; ++j) {
        const double x0 = sp->table_x[j], x1 = sp->table_x[j + 1u];
        if (x <= x1) {
            const double f = (x - x0) / (x1 - x0);
            return (sp->table_p[j] + f * (sp->table_p[j + 1u] - sp->table_p[j])) / mass;
        }
    }
    return 0.0;
}

static double table_mass(const hstpf_dist_spec_t *sp)
{
    double m = 0.0;
    uint16_t j;
    for (j = 0; j + 1u < sp->table_n; ++j) {
        m += 0.5 * (sp->table_p[j] + sp->table_p[j + 1u]) * (sp->table_x[j + 1u] - sp->table_x[j]);
    }
    return m;
}

/* Lower (upper = 0) or upper (upper = 1) tail probability at x. */
static double tail_prob(const hstpf_dist_spec_t *sp, double mass, double x, int upper)
{
    double p, q;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        return 0.5 * erfc((upper ? 1.0 : -1.0) * (x - sp->mean) / (sp->sd * sqrt(2.0)));
    case HSTPF_DIST_GAMMA:
        gamma_pq(sp->shape, (x - sp->loc) / sp->scale, &p, &q);
        return upper ? q : p;
    default:
        p = table_cdf(sp, mass, x);
        return upper ? 1.0 - p : p;
    }
}

/* x with lower (or upper) tail probability prob, by bisection. The Gamma is
 * bisected in log(x - loc) so that quantiles near its edge (1e-300 for
 * small shapes) stay exact. */
static double quantile(const hstpf_dist_spec_t *sp, double mass, double prob, int upper)
{
    double a, b;
    int i, logscale = 0;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        a = sp->mean - 40.0 * sp->sd;
        b = sp->mean + 40.0 * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        logscale = 1; /* in log((x - loc) / scale): the bracket is in scales */
        a = -745.0;
        b = log(sp->shape + 40.0 * sqrt(sp->shape) + 800.0);
        break;
    default:
        a = sp->table_x[0];
        b = sp->table_x[sp->table_n - 1u];
        break;
    }
    for (i = 0; i < 200; ++i) {
        const double mid = 0.5 * (a + b);
        const double x = logscale ? sp->loc + sp->scale * exp(mid) : mid;
        const double tp = tail_prob(sp, mass, x, upper);
        /* the lower tail grows with x, the upper one shrinks */
        if ((upper == 0) == (tp < prob)) {
            a = mid;
        } else {
            b = mid;
        }
    }
    return logscale ? sp->loc + sp->scale * exp(0.5 * (a + b)) : 0.5 * (a + b);
}

static double exact_logpdf(const hstpf_dist_spec_t *sp, double mass, double x)
{
    double z, p;
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        z = (x - sp->mean) / sp->sd;
        return -0.5 * z * z - log(sp->sd * sqrt(2.0 * 3.14159265358979323846));
    case HSTPF_DIST_GAMMA:
        z = (x - sp->loc) / sp->scale;
        if (z <= 0.0) {
            return -HUGE_VAL;
        }
        return (sp->shape - 1.0) * log(z) - z - log(sp->scale) - lgamma(sp->shape);
    default:
        p = table_pdf(sp, mass, x);
        return p > 0.0 ? log(p) : -HUGE_VAL;
    }
}

static int finite_d(double x)
{
    return isfinite(x) ? 1 : 0;
}

/* A spread (sd, scale, support width, soft edge) the float tables can hold
 * around an offset (mean, location, table end). */
static int spread_ok(double spread, double offset)
{
    return spread >= HSTPF_DIST_SPREAD_MIN && spread <= HSTPF_DIST_SPREAD_MAX &&
           spread >= HSTPF_DIST_REL_MIN * fabs(offset);
}

int32_t hstpf__dist_check(const hstpf_dist_spec_t *sp)
{
    uint16_t j;
    if (sp == NULL) {
        return HSTPF_E_NULL;
    }
    if (!finite_d(sp->floor_depth) || !finite_d(sp->edge_soft)) {
        return HSTPF_E_NONFINITE;
    }
    if (sp->floor_depth < 0.0 || sp->floor_depth > HSTPF_DIST_FLOOR_MAX || sp->edge_soft < 0.0 ||
        (sp->edge_soft > 0.0 && !spread_ok(sp->edge_soft, 0.0))) {
        return HSTPF_E_DIST;
    }
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        if (!finite_d(sp->mean) || !finite_d(sp->sd)) {
            return HSTPF_E_NONFINITE;
        }
        return fabs(sp->mean) <= HSTPF_DIST_X_MAX && spread_ok(sp->sd, sp->mean) ? HSTPF_OK : HSTPF_E_DIST;
    case HSTPF_DIST_GAMMA:
        if (!finite_d(sp->shape) || !finite_d(sp->scale) || !finite_d(sp->loc)) {
            return HSTPF_E_NONFINITE;
        }
        return (sp->shape >= 1e-3 && sp->shape <= 1e4 && fabs(sp->loc) <= HSTPF_DIST_X_MAX &&
                spread_ok(sp->scale, sp->loc))
                   ? HSTPF_OK
                   : HSTPF_E_DIST;
    case HSTPF_DIST_TABLE:
        if (sp->table_x == NULL || sp->table_p == NULL) {
            return HSTPF_E_NULL;
        }
        if (sp->table_n < 2u || sp->table_n > HSTPF_DIST_TABLE_MAX) {
            return HSTPF_E_SIZE;
        }
        for (j = 0; j < sp->table_n; ++j) {
            if (!finite_d(sp->table_x[j]) || !finite_d(sp->table_p[j])) {
                return HSTPF_E_NONFINITE;
            }
            if (sp->table_p[j] < 0.0 || fabs(sp->table_x[j]) > HSTPF_DIST_X_MAX ||
                (j > 0u && !(sp->table_x[j] > sp->table_x[j - 1u]))) {
                return HSTPF_E_DIST;
            }
        }
        {
            const double x0 = sp->table_x[0], x1 = sp->table_x[sp->table_n - 1u];
            const double mass = table_mass(sp); /* overflows to inf for huge densities */
            return spread_ok(x1 - x0, fabs(x0) > fabs(x1) ? x0 : x1) && mass > 0.0 && finite_d(mass)
                       ? HSTPF_OK
                       : HSTPF_E_DIST;
        }
    default:
        return HSTPF_E_DIST;
    }
}

int32_t hstpf_dist_init(hstpf_dist_t *d, const hstpf_dist_spec_t *sp)
{
    const double depth = (sp != NULL && sp->floor_depth > 0.0) ? sp->floor_depth : DEFAULT_FLOOR_DEPTH;
    double mass = 1.0, lo, hi, dx, lpmax = -HUGE_VAL, mean, var;
    int32_t err;
    uint32_t i;
    int k;

    if (d == NULL) {
        return HSTPF_E_NULL;
    }
    err = hstpf__dist_check(sp);
    if (err != HSTPF_OK) {
        return err;
    }
    if (sp->kind == HSTPF_DIST_TABLE) {
        mass = table_mass(sp);
    }

    /* inverse CDF: body nodes, then the two geometric tail tables */
    for (i = 1; i < HSTPF_DIST_QN; ++i) {
        const double u = (double)i / (double)HSTPF_DIST_QN;
        d->q[i] = (hstpf_real_t)(u <= 0.5 ? quantile(sp, mass, u, 0) : quantile(sp, mass, 1.0 - u, 1));
    }
    for (k = 0; k < HSTPF_DIST_TAILN; ++k) {
        const double p = ldexp(1.0, k - 32);
        d->tail_lo[k] = (hstpf_real_t)quantile(sp, mass, p, 0);
        d->tail_hi[k] = (hstpf_real_t)quantile(sp, mass, p, 1);
    }
    d->q[0] = d->tail_lo[0];
    d->q[HSTPF_DIST_QN] = d->tail_hi[0];

    /* log-density grid over the body, and the tails beyond it */
    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN:
        lo = sp->mean - 8.0 * sp->sd;
        hi = sp->mean + 8.0 * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        lo = sp->loc;
        hi = quantile(sp, mass, GAMMA_TOP_TAIL, 1);
        break;
    default:
        lo = sp->table_x[0];
        hi = sp->table_x[sp->table_n - 1u];
        break;
    }
    dx = (hi - lo) / (double)(HSTPF_DIST_LN - 1);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        double v = exact_logpdf(sp, mass, lo + dx * (double)i);
        if (i == 0u && sp->kind == HSTPF_DIST_GAMMA && sp->shape < 1.0) {
            /* unbounded density at the edge: average over the half cell */
            double p, q;
            gamma_pq(sp->shape, 0.5 * dx / sp->scale, &p, &q);
            v = log(p / (0.5 * dx));
        }
        if (v > lpmax) {
            lpmax = v;
        }
        d->lp[i] = (hstpf_real_t)v; /* -inf until clamped below */
    }
    d->lp_max = (hstpf_real_t)lpmax;
    d->floor = (hstpf_real_t)(lpmax - depth);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        if (!(d->lp[i] > d->floor)) {
            d->lp[i] = d->floor;
        }
    }
    d->lo = (hstpf_real_t)lo;
    d->dx = (hstpf_real_t)dx;
    d->inv_dx = (hstpf_real_t)(1.0 / dx);

    switch (sp->kind) {
    case HSTPF_DIST_GAUSSIAN: /* exact quadratic continuation */
        d->hard[0] = d->hard[1] = 0u;
        d->tail_b[0] = d->tail_b[1] = (hstpf_real_t)(-8.0 / sp->sd);
        d->tail_c[0] = d->tail_c[1] = (hstpf_real_t)(-0.5 / (sp->sd * sp->sd));
        mean = sp->mean;
        var = sp->sd * sp->sd;
        break;
    case HSTPF_DIST_GAMMA:
        d->hard[0] = 1u;
        d->hard[1] = 0u;
        d->tail_b[1] = (hstpf_real_t)((sp->shape - 1.0) / (hi - lo) - 1.0 / sp->scale);
        d->tail_c[1] = 0;
        mean = sp->loc + sp->shape * sp->scale;
        var = sp->shape * sp->scale * sp->scale;
        break;
    default: {
        uint16_t j;
        double m0 = 0.0, m1 = 0.0, m2 = 0.0, pmax = 0.0;
        const double x0 = sp->table_x[0];
        d->hard[0] = d->hard[1] = 1u;
        for (j = 0; j < sp->table_n; ++j) {
            pmax = sp->table_p[j] > pmax ? sp->table_p[j] : pmax;
        }
        /* exact moments of a piecewise-linear density, about x[0] and with
         * p / max p: no overflow for densities up to 1e308 or offsets 1e9 */
        for (j = 0; j + 1u < sp->table_n; ++j) {
            const double a = sp->table_x[j] - x0, b = sp->table_x[j + 1u] - x0;
            const double pa = sp->table_p[j] / pmax, pb = sp->table_p[j + 1u] / pmax, h = b - a;
            m0 += 0.5 * (pa + pb) * h;
            m1 += h * (pa * (2.0 * a + b) + pb * (a + 2.0 * b)) / 6.0;
            m2 += h * (pa * (3.0 * a * a + 2.0 * a * b + b * b) + pb * (a * a + 2.0 * a * b + 3.0 * b * b)) / 12.0;
        }
        mean = m1 / m0;
        var = m2 / m0 - mean * mean;
        mean += x0;
        break;
    }
    }
    for (k = 0; k < 2; ++k) {
        if (d->hard[k]) {
            d->tail_b[k] = 0;
            d->tail_c[k] = sp->edge_soft > 0.0 ? (hstpf_real_t)(-0.5 / (sp->edge_soft * sp->edge_soft)) : (hstpf_real_t)0;
        }
    }
    d->mean = (hstpf_real_t)mean;
    d->sd = (hstpf_real_t)sqrt(var > 0.0 ? var : 0.0);
    d->floor_slope = (hstpf_real_t)(var > 0.0 ? 1.0 / sqrt(var) : 1.0 / dx);
    d->dd_max = (hstpf_real_t)(1e4 * (var > 0.0 ? sqrt(var) : dx));
    return HSTPF_OK;
}

hstpf_real_t hstpf_dist_sample(const hstpf_dist_t *d, uint32_t r)
{
    return hstpf__dist_sample(d, r);
}

hstpf_real_t hstpf_dist_logpdf(const hstpf_dist_t *d, hstpf_real_t x)
{
    return hstpf__dist_logpdf(d, x);
}

hstpf_real_t hstpf_exp_neg(hstpf_real_t x)
{
    return hstpf__exp_neg(x);
}

/* Density of Gamma(k, th) + N(0, sd) at x (loc removed), by quadrature.
 * For shape k < 1 the part [0, gc = sd] is integrated in u = (g/th)^k,
 * where the density is bounded (the edge singularity removed). The rest,
 * up to gmax, on a fixed midpoint grid of steps h = min(sd, sv) / 16, sv
 * the scale on which the Gamma's density varies; only the steps within
 * x +- 9 sd (the kernel's mass beyond is below 1e-17) and above glo (the
 * Gamma's mass below is negligible) are visited, so the work per node is
 * bounded whatever th / sd: 2 x 9 x 16 steps when sd <= sv, else the
 * Gamma's own span [glo, gmax] in steps of sv / 16 (about 1500 at most).
 * Init time only. */
#define BLUR_Z 9.0
#define BLUR_STEPS 16.0
#define BLUR_NU 256
#define BLUR_MAX_STEPS 1e7 /* never reached in the ranges; keeps the casts defined */
typedef struct {
    double k, th, sd;  /* shape, scale, blur */
    double gc, gmax;   /* u-part [0, gc]; grid part [gc, gmax] */
    double glo;        /* no Gamma mass worth counting below */
    double dg, ng;     /* grid step and number of steps */
    double ig, lnorm;  /* 1 / (Gamma(k) th^k) and its log */
} blur_q_t;

static double gamma_blur_pdf(const blur_q_t *q, double x)
{
    const double k = q->k, th = q->th, sd = q->sd;
    const double inorm = 1.0 / (sd * sqrt(2.0 * 3.14159265358979323846));
    double acc = 0.0, z, jlo, jhi;
    int j, j0, j1;
    if (q->gc > 0.0) {
        /* p_G dg = e^(-g/th) du / Gamma(k + 1) */
        const double umax = pow(q->gc / th, k);
        const double lgk1 = lgamma(k + 1.0);
        for (j = 0; j < BLUR_NU; ++j) {
            const double u = umax * ((double)j + 0.5) / (double)BLUR_NU, g = th * pow(u, 1.0 / k);
            z = (x - g) / sd;
            acc += exp(-g / th - lgk1) * (umax / (double)BLUR_NU) * exp(-0.5 * z * z) * inorm;
        }
    }
    if (q->ng < 1.0) {
        return acc;
    }
    /* the grid steps that can lie within x +- 9 sd, one spare on each side */
    jlo = floor(((x - BLUR_Z * sd > q->glo ? x - BLUR_Z * sd : q->glo) - q->gc) / q->dg) - 1.0;
    jhi = ceil((x + BLUR_Z * sd - q->gc) / q->dg) + 1.0;
    jlo = jlo > 0.0 ? jlo : 0.0;
    jhi = jhi < q->ng ? jhi : q->ng;
    if (!(jhi > jlo)) {
        return acc;
    }
    j0 = (int)jlo;
    j1 = (int)jhi;
    for (j = j0; j < j1; ++j) {
        const double g = q->gc + q->dg * ((double)j + 0.5);
        z = (x - g) / sd;
        if (z > -BLUR_Z && z < BLUR_Z) {
            if (k < 1.0) { /* p_G(g) = ig g^(k-1) e^(-g/th): bounded for g >= gc */
                acc += q->ig * pow(g, k - 1.0) * exp(-g / th) * q->dg * exp(-0.5 * z * z) * inorm;
            } else { /* in logs: g^(k-1) and Gamma(k) overflow for large shapes */
                acc += exp(q->lnorm + (k - 1.0) * log(g) - g / th - 0.5 * z * z) * q->dg * inorm;
            }
        }
    }
    return acc;
}

int32_t hstpf__dist_blur(hstpf_dist_t *d, const hstpf_dist_spec_t *sp, double sd)
{
    const double depth = sp->floor_depth > 0.0 ? sp->floor_depth : DEFAULT_FLOOR_DEPTH;
    const double k = sp->shape, th = sp->scale;
    double lo, hi, right, dx, lpmax = -HUGE_VAL, var, slope, sv, h;
    blur_q_t q;
    uint32_t i;
    if (!finite_d(sd) || !spread_ok(sd, 0.0) || sp->kind != HSTPF_DIST_GAMMA || hstpf__dist_check(sp) != HSTPF_OK) {
        return HSTPF_E_DIST; /* a Gaussian stays Gaussian: the caller adds the variances */
    }
    /* Grid from 6 sd left of the edge to the Gamma's 1 - 1e-9 quantile hi
     * (or 8 sd beyond its mean when the blur is that wide); the
     * convolution integrated 10 sd beyond, but not beyond 50 scales past
     * hi (1e-30 of the Gamma's mass there). A blur narrower than an eighth
     * of the grid's spacing cannot show between two nodes: it is widened
     * to hi / 4088. */
    hi = quantile(sp, 1.0, GAMMA_TOP_TAIL, 1) - sp->loc;
    q.sd = hi / (8.0 * (double)(HSTPF_DIST_LN - 1));
    q.sd = sd > q.sd ? sd : q.sd;
    right = k * th + 8.0 * q.sd;
    right = right > hi ? right : hi;
    lo = -6.0 * q.sd;
    dx = (right - lo) / (double)(HSTPF_DIST_LN - 1);
    q.k = k;
    q.th = th;
    q.gmax = right + 10.0 * q.sd;
    q.gmax = q.gmax < hi + 50.0 * th ? q.gmax : hi + 50.0 * th;
    q.gc = k < 1.0 ? (q.sd < q.gmax ? q.sd : q.gmax) : 0.0;
    /* a large shape's left tail 12 sd below its mean is below e^-72 */
    q.glo = k > 144.0 ? (k - 12.0 * sqrt(k)) * th : 0.0;
    sv = th * sqrt(k > 1.0 ? k : 1.0);
    h = (q.sd < sv ? q.sd : sv) / BLUR_STEPS;
    q.ng = ceil((q.gmax - q.gc) / h);
    q.ng = q.ng < BLUR_MAX_STEPS ? q.ng : BLUR_MAX_STEPS;
    q.dg = q.ng >= 1.0 ? (q.gmax - q.gc) / q.ng : 0.0;
    q.ig = 1.0 / (exp(lgamma(k)) * pow(th, k)); /* used for k < 1 only: finite there */
    q.lnorm = -lgamma(k) - k * log(th);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        const double p = gamma_blur_pdf(&q, lo + dx * (double)i);
        const double v = p > 0.0 ? log(p) : -HUGE_VAL;
        lpmax = v > lpmax ? v : lpmax;
        d->lp[i] = (hstpf_real_t)v;
    }
    d->lp_max = (hstpf_real_t)lpmax;
    d->floor = (hstpf_real_t)(lpmax - depth);
    for (i = 0; i < HSTPF_DIST_LN; ++i) {
        if (!(d->lp[i] > d->floor)) {
            d->lp[i] = d->floor;
        }
    }
    d->lo = (hstpf_real_t)(lo + sp->loc);
    d->dx = (hstpf_real_t)dx;
    d->inv_dx = (hstpf_real_t)(1.0 / dx);
    /* left: the Gaussian's quadratic from the edge's slope; right: linear,
     * the Gamma's own slope, or the end slope when the grid was widened for
     * a wide blur; neither rising away from the grid */
    d->hard[0] = d->hard[1] = 0u;
    slope = ((double)d->lp[1] - (double)d->lp[0]) / dx;
    d->tail_b[0] = (hstpf_real_t)(-slope < 0.0 ? -slope : 0.0);
    d->tail_c[0] = (hstpf_real_t)(-0.5 / (q.sd * q.sd));
    slope = right > hi ? ((double)d->lp[HSTPF_DIST_LN - 1] - (double)d->lp[HSTPF_DIST_LN - 2]) / dx
                       : (k - 1.0) / hi - 1.0 / th;
    d->tail_b[1] = (hstpf_real_t)(slope < 0.0 ? slope : 0.0);
    d->tail_c[1] = 0;
    var = k * th * th + q.sd * q.sd;
    d->sd = (hstpf_real_t)sqrt(var);
    d->floor_slope = (hstpf_real_t)(1.0 / sqrt(var));
    d->dd_max = (hstpf_real_t)(1e4 * sqrt(var));
    return HSTPF_OK;
}

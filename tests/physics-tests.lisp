;;;; tests/physics-tests.lisp -- GENERATED from physics.org by 'make tangle'. Do not edit.

;; [[file:../physics.org::#BJSCR8][Claims are tests:1]]
(defpackage #:luv-physics-tests
  (:use #:cl #:luv-physics)
  (:local-nicknames (#:5am #:fiveam))
  (:documentation "The claims of physics.org, as FiveAM tests. #BJSCR8")
  (:export #:define-claim #:check #:claims #:*claims*))

(in-package #:luv-physics-tests)

(5am:def-suite claims
  :description "Every claim of physics.org; one nested suite per anchor. #BJSCR8")

(defvar *claims* '()
  "The claims of the page in the order they were defined, each (ANCHOR . NAME). #BJSCR8")

(eval-when (:compile-toplevel :load-toplevel :execute)
  (defun anchor-string-p (object)
    "True if OBJECT is an anchor: a string of six uppercase letters or digits. #BJSCR8"
    (and (stringp object)
         (= 6 (length object))
         (every (lambda (c) (or (char<= #\A c #\Z) (char<= #\0 c #\9))) object))))

(defun record-claim (anchor name)
  "Note claim NAME of section ANCHOR in *CLAIMS* and make sure ANCHOR's suite exists. #BJSCR8"
  (let ((suite (intern anchor '#:luv-physics-tests)))
    (unless (typep (5am:get-test suite) '5am::test-suite)
      (5am:make-suite suite :in 'claims
                            :description (format nil "The claims of section ~A." anchor)))
    (setf *claims* (append (remove name *claims* :key #'cdr)
                           (list (cons anchor name))))
    name))

(defmacro define-claim (anchor name docstring &body body)
  "Define claim NAME of section ANCHOR: a FiveAM test described \"ANCHOR: DOCSTRING\". #BJSCR8"
  (unless (anchor-string-p anchor)
    (error "define-claim: ~S is not an anchor (six uppercase letters or digits, as a string)." anchor))
  (check-type name (and symbol (not null)))
  (check-type docstring string)
  `(progn
     (record-claim ,anchor ',name)
     (5am:test (,name :suite ,(intern anchor '#:luv-physics-tests))
       ,(format nil "~A: ~A" anchor docstring)
       ,@body)))

(defmacro check (form &rest reason-args)
  "Assert FORM in a claim; REASON-ARGS, if any, are a format control and its arguments. #BJSCR8"
  `(5am:is ,form ,@reason-args))
;; Claims are tests:1 ends here

;; [[file:../physics.org::#BJSCR8][BJSCR8-claims-carry-their-anchor]]
(define-claim "BJSCR8" claims-carry-their-anchor
    "Each recorded claim is a test in its anchor's suite, described \"ANCHOR: ...\"."
  (check (member '("BJSCR8" . claims-carry-their-anchor) *claims* :test #'equal))
  (loop for (anchor . name) in *claims*
        for test = (5am:get-test name)
        for suite = (5am:get-test (find-symbol anchor '#:luv-physics-tests))
        do (check (typep test '5am::test-case) "~A is not a test" name)
           (check (and test (eql 0 (search (format nil "~A: " anchor) (5am::description test))))
                  "~A: description does not start with its anchor" name)
           (check (and suite (gethash name (5am::tests suite)))
                  "~A is not in the suite of ~A" name anchor)))
;; BJSCR8-claims-carry-their-anchor ends here

;; [[file:../physics.org::#BJSCR8][BJSCR8-define-claim-rejects-bad-anchors]]
(define-claim "BJSCR8" define-claim-rejects-bad-anchors
    "Anchors that are lowercase, too short or not strings are refused at expansion."
  (flet ((refused-p (anchor)
           (handler-case (progn (macroexpand-1 `(define-claim ,anchor probe "Probe.")) nil)
             (error () t))))
    (check (refused-p "bjscr8"))
    (check (refused-p "BJSCR"))
    (check (refused-p 'bjscr8))
    (check (not (refused-p "BJSCR8")))))
;; BJSCR8-define-claim-rejects-bad-anchors ends here

;; [[file:../physics.org::#BJSCR8][BJSCR8-check-is-the-framework-assertion]]
(define-claim "BJSCR8" check-is-the-framework-assertion
    "CHECK expands to 5AM:IS with the same arguments."
  (check (equal '(5am:is (= 1 1) "why ~A" 2)
                (macroexpand-1 '(check (= 1 1) "why ~A" 2)))))
;; BJSCR8-check-is-the-framework-assertion ends here

;; [[file:../physics.org::#HAPODD][HAPODD-records-have-the-documented-keys]]
(define-claim "HAPODD" records-have-the-documented-keys
    "A record is a plist of :name :kind :anchor :file :line :org-line :docstring."
  (let ((records (anchor-definitions "HAPODD")))
    (check (= 3 (length records)))
    (dolist (record records)
      (check (equal '(:name :kind :anchor :file :line :org-line :docstring)
                    (loop for key in record by #'cddr collect key))))))
;; HAPODD-records-have-the-documented-keys ends here

;; [[file:../physics.org::#2HB3Y9][2HB3Y9-scan-finds-definitions]]
(define-claim "2HB3Y9" scan-finds-definitions
    "Scanning tangled text yields name, kind, line, anchor and docstring of each definition."
  (flet ((link (anchor label)
           (let ((open "[[") (close "]]"))
             (concatenate 'string ";; " open "file:../physics.org::#" anchor "][" label close))))
    (let* ((text (format nil "~{~A~%~}"
                         (list "(in-package #:luv-physics-tests)"
                               ""
                               (link "AAAAAA" "Sample:1")
                               "(defun sample-function (x)"
                               "  \"Return X. #AAAAAA\""
                               "  x)"
                               "(eval-when (:compile-toplevel :load-toplevel :execute)"
                               "  (defparameter *sample* 1 \"A sample. #AAAAAA\"))"
                               ""
                               (link "BBBBBB" "Other:1")
                               "(define-sample-layout sample-layout \"Columns. #BBBBBB\" (x single-float))"
                               "(defmethod sample-generic ((x integer)) x)")))
           (records (luv-physics::scan-tangled-text text)))
      (flet ((all (key) (mapcar (lambda (r) (getf r key)) records)))
        (check (equal '(sample-function *sample* sample-layout sample-generic) (all :name)))
        (check (equal '(:defun :defparameter :define-sample-layout :defmethod) (all :kind)))
        (check (equal '(4 7 11 12) (all :line)))
        (check (equal '("AAAAAA" "AAAAAA" "BBBBBB" "BBBBBB") (all :anchor)))
        (check (equal '("Return X. #AAAAAA" "A sample. #AAAAAA" "Columns. #BBBBBB" nil)
                      (all :docstring)))))))
;; 2HB3Y9-scan-finds-definitions ends here

;; [[file:../physics.org::#2HB3Y9][2HB3Y9-link-comments-only]]
(define-claim "2HB3Y9" link-comments-only
    "LINK-COMMENT-ANCHOR accepts ';; ' plus a file link to ::#ANCHOR, nothing else."
  (let ((open "[[") (close "]]"))
    (flet ((anchor (&rest parts) (luv-physics::link-comment-anchor (apply #'concatenate 'string parts))))
      (check (equal "ABC123" (anchor ";; " open "file:../physics.org::#ABC123][Heading:2" close)))
      (check (equal "../physics.org"
                    (nth-value 1 (anchor ";; " open "file:../physics.org::#ABC123][x" close))))
      (check (null (anchor ";;; see " open "file:../physics.org::#ABC123][x" close)))
      (check (null (anchor "  ;; " open "file:../physics.org::#ABC123][x" close)))
      (check (null (anchor ";; " open "file:../physics.org::*Heading][x" close))))))
;; 2HB3Y9-link-comments-only ends here

;; [[file:../physics.org::#UIQ8J5][UIQ8J5-page-line-matches-tangled-line]]
(define-claim "UIQ8J5" page-line-matches-tangled-line
    "Each record's :org-line of physics.org equals its :line of the tangled file."
  (let ((page (luv-physics::split-lines
               (luv-physics::read-file-text
                (asdf:system-relative-pathname "luv-physics" "physics.org"))))
        (files (make-hash-table :test 'equal)))
    (check (< 10 (length luv-physics::*definitions*)))
    (dolist (record luv-physics::*definitions*)
      (destructuring-bind (&key name file line org-line &allow-other-keys) record
        (let ((tangled (or (gethash file files)
                           (setf (gethash file files)
                                 (luv-physics::split-lines
                                  (luv-physics::read-file-text
                                   (asdf:system-relative-pathname "luv-physics" file)))))))
          (check (and org-line
                      (string= (aref tangled (1- line))
                               (luv-physics::unescape-org-line (aref page (1- org-line)))))
                 "~S: ~A:~A is not physics.org:~A" name file line org-line))))))
;; UIQ8J5-page-line-matches-tangled-line ends here

;; [[file:../physics.org::#UIQ8J5][UIQ8J5-unescape-removes-one-comma]]
(define-claim "UIQ8J5" unescape-removes-one-comma
    "UNESCAPE-ORG-LINE drops one comma before *, #+ or more commas, keeping indentation."
  (loop for (stored tangled) in '((",* heading" "* heading")
                                  ("  ,#+begin_src" "  #+begin_src")
                                  (",,* stays escaped once" ",* stays escaped once")
                                  ("(list ,a ,@b)" "(list ,a ,@b)")
                                  (",x" ",x")
                                  ("" ""))
        do (check (string= tangled (luv-physics::unescape-org-line stored))
                  "~S should tangle to ~S" stored tangled)))
;; UIQ8J5-unescape-removes-one-comma ends here

;; [[file:../physics.org::#BSOZ3U][BSOZ3U-definition-anchor-finds-its-section]]
(define-claim "BSOZ3U" definition-anchor-finds-its-section
    "DEFINITION-ANCHOR of ANCHOR-DEFINITIONS is BSOZ3U and the page line of its defun."
  (let ((page (luv-physics::split-lines
               (luv-physics::read-file-text
                (asdf:system-relative-pathname "luv-physics" "physics.org")))))
    (multiple-value-bind (anchor org-line) (definition-anchor 'anchor-definitions)
      (check (equal "BSOZ3U" anchor))
      (check (eql org-line (1+ (position "(defun anchor-definitions (anchor)" page
                                         :test #'string=)))))
    (check (equal "BSOZ3U" (definition-anchor 'anchor-definitions :defun)))
    (check (null (definition-anchor 'anchor-definitions :defvar)))
    (check (null (definition-anchor 'no-such-definition)))))
;; BSOZ3U-definition-anchor-finds-its-section ends here

;; [[file:../physics.org::#BSOZ3U][BSOZ3U-anchor-definitions-by-section]]
(define-claim "BSOZ3U" anchor-definitions-by-section
    "ANCHOR-DEFINITIONS lists the package of NEZQ3X and the functions of BSOZ3U."
  (let ((package (anchor-definitions "NEZQ3X")))
    (check (equal '(("LUV-PHYSICS" :defpackage))
                  (mapcar (lambda (r) (list (getf r :name) (getf r :kind))) package))))
  (check (equal "NEZQ3X" (definition-anchor "LUV-PHYSICS" :defpackage)))
  (check (equal '(luv-physics::register-tangled-file anchor-definitions definition-anchor)
                (mapcar (lambda (r) (getf r :name)) (anchor-definitions "BSOZ3U"))))
  (check (equal (anchor-definitions "BSOZ3U") (anchor-definitions "#BSOZ3U")))
  (check (null (anchor-definitions "ZZZZZ9"))))
;; BSOZ3U-anchor-definitions-by-section ends here

;; [[file:../physics.org::#JKM0PY][JKM0PY-scalar-first]]
(define-claim "JKM0PY" scalar-first
    "AVAILABLE-KERNEL-FAMILIES starts with :SCALAR and lists known families once each."
  (let ((families (available-kernel-families)))
    (check (eq :scalar (first families)))
    (check (equal families (remove-duplicates families)))
    (check (subsetp (rest families)
                    (mapcar #'first luv-physics::*kernel-family-instruction-sets*)))))
;; JKM0PY-scalar-first ends here

;; [[file:../physics.org::#JKM0PY][JKM0PY-families-match-cpuinfo]]
(define-claim "JKM0PY" families-match-cpuinfo
    "A wide family is offered exactly when /proc/cpuinfo lists its flags."
  (flet ((split-words (text)
           (loop for start = (position #\Space text :test-not #'char=)
                   then (position #\Space text :test-not #'char= :start end)
                 for end = (and start (or (position #\Space text :start start) (length text)))
                 while start
                 collect (subseq text start end)))
         (flags-line (stream)
           (loop for line = (read-line stream nil)
                 while line
                 when (eql 0 (search "flags" line))
                   return (substitute #\Space #\Tab (subseq line (1+ (position #\: line)))))))
    (let ((flags (with-open-file (in "/proc/cpuinfo" :if-does-not-exist nil)
                   (let ((line (and in (flags-line in))))
                     (and line (split-words line)))))
          (families (available-kernel-families)))
      (check (member :scalar families))
      (when flags
        (loop for (family . needed) in '((:sse "sse4_1") (:avx2 "avx2"))
              for listed = (every (lambda (flag) (member flag flags :test #'string=)) needed)
              do (check (eq (and listed t) (and (member family families) t))
                        "~S is ~:[not ~;~]offered, but /proc/cpuinfo ~:[lacks~;lists~] ~{~A~^ ~}"
                        family (member family families) listed needed))))))
;; JKM0PY-families-match-cpuinfo ends here

;; [[file:../physics.org::#7PAQ3M][7PAQ3M-families-agree-bit-for-bit]]
(define-claim "7PAQ3M" families-agree-bit-for-bit
    "Each available family's hash equals the scalar hash on the 200-ball and 1000-ball piles."
  (flet ((hash-after (balls steps kernels)
           (let ((world (make-basin-world balls :kernels kernels)))
             (dotimes (i steps) (step-physics-world world))
             (physics-world-state-hash world))))
    (let ((families (mapcar #'first (remove-if-not #'luv-physics::kernel-family-available-p
                                                   luv-physics::*kernel-families*))))
      (check (member :avx2 families) "the AVX2 family is registered and this CPU runs it")
      (loop for (balls steps) in '((200 120) (1000 200))
            for reference = (hash-after balls steps :scalar)
            do (dolist (family (remove :scalar families))
                 (check (= reference (hash-after balls steps family))
                        "~A differs from scalar after ~D steps of ~D balls" family steps balls))))))
;; 7PAQ3M-families-agree-bit-for-bit ends here

;; [[file:../physics.org::#7PAQ3M][7PAQ3M-choosing-a-family]]
(define-claim "7PAQ3M" choosing-a-family
    "An unknown family signals; :auto is the last available family."
  (check (typep (handler-case (make-physics-world :kernels :neon) (error (e) e))
                'invalid-physics-parameter))
  (let ((widest (car (last (remove-if-not #'luv-physics::kernel-family-available-p
                                          luv-physics::*kernel-families*)))))
    (check (eq (second widest)
               (class-name (class-of (luv-physics::physics-world-kernels
                                      (make-physics-world :kernels :auto))))))))
;; 7PAQ3M-choosing-a-family ends here

;; [[file:../physics.org::#O07FDP][O07FDP-both-files-registered]]
(define-claim "O07FDP" both-files-registered
    "The registry holds tangled/physics.lisp and tangled/physics-simd.lisp, in load order."
  (check (equal '("physics.lisp" "physics-simd.lisp")
                (mapcar #'file-namestring luv-physics::*registered-files*)))
  (check (equal '("tangled/physics.lisp" "tangled/physics-simd.lisp")
                (remove-duplicates (mapcar (lambda (r) (getf r :file)) luv-physics::*definitions*)
                                   :test #'equal :from-end t))))
;; O07FDP-both-files-registered ends here

;; [[file:../physics.org::#O07FDP][O07FDP-every-definition-is-placed]]
(define-claim "O07FDP" every-definition-is-placed
    "Every registered record has an anchor and an org line."
  (dolist (record luv-physics::*definitions*)
    (check (and (getf record :anchor) (getf record :org-line))
           "~S at ~A:~A is not placed on the page"
           (getf record :name) (getf record :file) (getf record :line))))
;; O07FDP-every-definition-is-placed ends here

;; [[file:../physics.org::#O07FDP][O07FDP-every-export-means-something]]
(define-claim "O07FDP" every-export-means-something
    "Each exported symbol of LUV-PHYSICS is defined on the page or known to the image."
  (do-external-symbols (symbol '#:luv-physics)
    (check (or (definition-anchor symbol)
               (fboundp symbol)
               (boundp symbol)
               (find-class symbol nil)
               (sb-ext:valid-type-specifier-p symbol))
           "~S is exported but means nothing" symbol)))
;; O07FDP-every-export-means-something ends here
